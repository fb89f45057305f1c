#include "agent/online_block_solver.hpp"

#include <algorithm>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/online/online_engine.hpp>

#include "agent/online_takeover_step.hpp"

namespace tessera::agent {

SolveOutcome OnlineBlockSolver::solve(runtime::OnlineAgentView& view, bool certify, bool climb,
                                      const RunRounds& run_rounds) {
  SolveOutcome out;
  own_ids_.clear();
  own_data_.clear();
  const GraphStream* stream = view.stream();
  if (!stream || view.own_block() < 0) return out;  // nothing of ours to solve yet
  // This agent's block problem is kept from solve to solve and grown with the new data.
  if (!live_)
    live_ = std::make_unique<LiveBlocks>(stream->graph().d, options_.solver.block_update,
                                         live_refactor_growth(options_), view.own_block());
  live_->sync(stream->graph(), view.owner(), view.iterate());
  const int c = live_->compact_block(view.own_block());
  if (live_->graph().num_poses == 0 || c < 0) return out;
  // A step's solve (Newton steps from the warm start by default); the certified one is the
  // plain solver's, from a converged iterate.
  DistributedOptions solver = certify ? options_.solver : online_step_solver(options_);
  solver.certify = certify;
  solver.round_result = false;
  // A certificate while the graph grows does not climb the staircase: the iterate keeps its
  // rank for the next data (a saddle is reported as not certified).
  if (!climb) solver.staircase.max_rank = solver.rank;
  use_online_refine_space(*live_, solver);
  const BlockLayout& layout = live_->layout();
  const auto& ids = layout.poses[static_cast<std::size_t>(c)];
  AgentState& state = *live_->states()[static_cast<std::size_t>(c)];
  CertifiedAgent agent(state, layout, solver);
  try {
    run_rounds(agent, static_cast<std::uint32_t>(c));
  } catch (const TakeoverNeeded&) {
    // The iterate so far is a valid point of the problem: the take-over starts from it.
    keep_own_poses(view, state, ids);
    throw;
  }
  keep_own_poses(view, state, ids);
  out.rounds = agent.total_rounds();
  const auto& last = agent.solves().back();
  out.stop_reason = last.stop_reason;
  out.grad_norm = last.trace.empty() ? 0.0 : last.trace.back().grad_norm;
  if (!last.trace.empty()) out.relaxation_cost = last.trace.back().cost;
  for (const NewtonRefineResult& n : agent.refines()) {
    out.newton_steps += n.steps;
    out.newton_cg_iterations += n.cg_iterations;
    out.newton_message_steps += n.message_steps();
    out.coarse_unknowns = std::max(out.coarse_unknowns, n.coarse_unknowns);
  }
  out.certified = agent.certified();
  if (!agent.certificates().empty())
    out.min_eigenvalue = agent.certificates().back().result.min_eigenvalue;
  return out;
}

long OnlineBlockSolver::robot_of_block(const runtime::OnlineAgentView& view,
                                       std::uint32_t b) const {
  if (!live_ || b >= live_->block_of().size()) return -1;
  return static_cast<long>(view.stream()->robots()[static_cast<std::size_t>(live_->block_of()[b])]);
}

void OnlineBlockSolver::keep_own_poses(runtime::OnlineAgentView& view, const AgentState& state,
                                       const std::vector<std::size_t>& ids) {
  // This agent's poses go out with the next report (the estimate made whole everywhere).
  const Eigen::Index w = live_->graph().d + 1;
  own_ids_.clear();
  own_rank_ = state.rank();
  const std::size_t per_pose = static_cast<std::size_t>(own_rank_ * w);
  own_data_.resize(ids.size() * per_pose);
  for (std::size_t s = 0; s < ids.size(); ++s) {
    own_ids_.push_back(static_cast<std::uint32_t>(live_->full_id()[ids[s]]));
    Eigen::Map<Eigen::MatrixXd>(own_data_.data() + s * per_pose, own_rank_, w) =
        state.Y.middleCols(w * static_cast<Eigen::Index>(s), w);
  }
  view.apply_block(own_ids_, own_data_, own_rank_);
}

}  // namespace tessera::agent
