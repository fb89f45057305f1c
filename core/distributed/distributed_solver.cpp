#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/distributed/trial_point_watch.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

const char* algorithm_name(DistributedAlgorithm a) {
  switch (a) {
    case DistributedAlgorithm::kRbcd:
      return "rbcd";
    case DistributedAlgorithm::kRbcdPlusPlus:
      return "rbcd++";
    case DistributedAlgorithm::kIrbcd:
      return "irbcd";
  }
  return "?";
}

DistributedAlgorithm parse_algorithm(const std::string& name) {
  if (name == "rbcd") return DistributedAlgorithm::kRbcd;
  if (name == "rbcd++") return DistributedAlgorithm::kRbcdPlusPlus;
  if (name == "irbcd") return DistributedAlgorithm::kIrbcd;
  throw InputError("algorithm '" + name + "' is not one of rbcd, rbcd++, irbcd");
}

void DistributedOptions::validate() const {
  auto fail = [](const char* field, const char* why) {
    throw InputError(std::string("DistributedOptions.") + field + " " + why);
  };
  if (rank < 2) fail("rank", "must be >= d (2 or 3)");
  if (robots < 0) fail("robots", "must be >= 0");
  if (!(grad_norm_tol >= 0)) fail("grad_norm_tol", "must be >= 0");
  if (max_rounds < 0) fail("max_rounds", "must be >= 0");
  if (threads < 1 || threads > 64) fail("threads", "must be in 1..64");
  if (!(rel_cost_decrease_tol >= 0)) fail("rel_cost_decrease_tol", "must be >= 0");
  block_update.validate();
  coarse.validate();
  local_rounds.validate();
  if (local_rounds.enabled && coarse.enabled)
    fail("local_rounds.enabled", "cannot be combined with coarse.enabled");
  if (irbcd_trust_region_steps < 0) fail("irbcd_trust_region_steps", "must be >= 0");
  if (!(irbcd_grad_reduction < 1)) fail("irbcd_grad_reduction", "must be < 1");
  algorithm_block_update().validate();
  rbcd_plus_plus.validate();
  irbcd.validate();
  if (refine.enabled) refine.validate();
  if (certify) {
    staircase.validate();
    if (staircase.max_rank < rank) fail("staircase.max_rank", "must be >= rank");
  }
}

BlockUpdateOptions DistributedOptions::algorithm_block_update() const {
  BlockUpdateOptions o = block_update;
  if (algorithm != DistributedAlgorithm::kIrbcd) return o;
  if (irbcd_trust_region_steps > 0) {
    o.trust_region_steps = irbcd_trust_region_steps;
    o.max_attempts = std::max(o.max_attempts, o.trust_region_steps);
  }
  if (irbcd_grad_reduction >= 0) o.grad_reduction = irbcd_grad_reduction;
  return o;
}

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Both entry points refuse bad options before any work; the rank check needs the graph's d,
// which DistributedOptions::validate() cannot know.
void check_options(const PoseGraph& graph, const DistributedOptions& options) {
  options.validate();
  if (options.rank < graph.d)
    throw InputError("DistributedOptions.rank must be >= d = " + std::to_string(graph.d));
}

}  // namespace

DistributedResult solve_distributed(const PoseGraph& graph, const std::vector<int>& assignment,
                                    const DistributedOptions& options,
                                    const std::vector<Pose>& initial) {
  const auto start = Clock::now();
  check_options(graph, options);
  // Checks the assignment before the (possibly costly) initial guess.
  const int N = make_block_layout(graph.num_poses, graph.measurements, assignment).num_blocks;
  std::vector<Pose> init = initial;
  if (init.empty())
    init = initial_poses(graph, options.initialization, options.robots > 0 ? options.robots : N);
  if (init.size() != graph.num_poses)
    throw InputError("distributed solve: initial guess has the wrong size");
  const double guess_s = since(start);
  DistributedResult res =
      solve_distributed_from_lifted(graph, assignment, options, lift_poses(init, options.rank));
  res.init_s += guess_s;
  res.wall_s = since(start);
  return res;
}

DistributedResult solve_distributed_from_lifted(const PoseGraph& graph,
                                                const std::vector<int>& assignment,
                                                const DistributedOptions& options,
                                                const Eigen::MatrixXd& X0, double known_grad_norm) {
  const auto start = Clock::now();
  check_options(graph, options);
  const Eigen::Index w = graph.d + 1;
  if (X0.rows() != options.rank || X0.cols() != w * static_cast<Eigen::Index>(graph.num_poses))
    throw InputError("distributed solve: lifted starting point is " + std::to_string(X0.rows()) +
                     " x " + std::to_string(X0.cols()) +
                     ", expected r x (d+1)n = " + std::to_string(options.rank) + " x " +
                     std::to_string(w * static_cast<Eigen::Index>(graph.num_poses)));
  const BlockLayout layout = make_block_layout(graph.num_poses, graph.measurements, assignment);
  const int N = layout.num_blocks;

  std::vector<std::unique_ptr<AgentState>> states;
  std::vector<AgentState*> pointers;
  for (int b = 0; b < N; ++b) {
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    const Eigen::MatrixXd Yb = gather_pose_columns(X0, ids, graph.d);
    states.push_back(std::make_unique<AgentState>(b, graph.d, layout, graph.measurements, Yb,
                                                  options.block_update));
    if (!std::isnan(known_grad_norm)) {
      // The neighbours' poses of X0, as the rounds' opening exchange would bring them.
      states.back()->reset_iterate(
          Yb, gather_pose_columns(X0, states.back()->problem().neighbors(), graph.d));
    }
    pointers.push_back(states.back().get());
  }
  if (options.coarse.enabled && options.coarse.space == CoarseSpaceKind::kSmoothed) {
    // Every agent would build this same space from the structure; in one process once.
    const auto space = std::make_shared<const CoarseSpace>(
        make_coarse_space(graph.num_poses, graph.measurements, assignment, options.coarse));
    for (AgentState* s : pointers) s->use_coarse_space(space, graph.measurements);
  }
  if (options.refine.enabled && options.refine.coarse == NewtonRefineOptions::Coarse::kSmoothed) {
    const auto space = std::make_shared<const CoarseSpace>(make_coarse_space(
        graph.num_poses, graph.measurements, assignment, options.refine.coarse_space_options()));
    for (AgentState* s : pointers) s->use_refine_space(space);
  }
  const double setup_s = since(start);
  DistributedResult res =
      solve_distributed_with_states(graph, layout, pointers, options, known_grad_norm);
  res.init_s += setup_s;
  res.wall_s = since(start);
  return res;
}

DistributedResult solve_distributed_with_states(const PoseGraph& graph, const BlockLayout& layout,
                                                const std::vector<AgentState*>& states,
                                                const DistributedOptions& options,
                                                double known_grad_norm) {
  return solve_distributed_watching_trials(graph, layout, states, options, {}, known_grad_norm);
}

DistributedResult solve_distributed_watching_trials(
    const PoseGraph& graph, const BlockLayout& layout, const std::vector<AgentState*>& states,
    const DistributedOptions& options, const TrialPointWatch& watch, double known_grad_norm) {
  const auto start = Clock::now();
  check_options(graph, options);
  const Eigen::Index w = graph.d + 1;
  const int N = layout.num_blocks;
  if (static_cast<int>(states.size()) != N || layout.owner.size() != graph.num_poses)
    throw std::invalid_argument(
        "distributed solve: one state per block of the graph's layout expected");
  DistributedResult res;
  res.agents = N;

  // One certified sequence per agent (with certification off: exactly the round protocol).
  std::vector<std::unique_ptr<CertifiedAgent>> sequences;
  std::vector<AgentProcess*> agents;
  for (int b = 0; b < N; ++b) {
    sequences.push_back(
        std::make_unique<CertifiedAgent>(*states[static_cast<std::size_t>(b)], layout, options));
    if (!std::isnan(known_grad_norm)) sequences.back()->set_known_start(known_grad_norm);
    if (watch)
      sequences.back()->set_trial_observer(
          [&watch, b](const Eigen::MatrixXd& Y, const Eigen::MatrixXd&) { watch(b, Y); });
    agents.push_back(sequences.back().get());
  }
  res.init_s = since(start);

  const auto solve_start = Clock::now();
  const std::clock_t cpu_start = std::clock();
  const DeliveryStats stats =
      run_in_process(agents, options.delivery, options.delivery_seed, options.threads);
  res.solve_s = since(solve_start);
  res.solve_cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  res.critical_path_cpu_s = stats.critical_path_cpu_s;

  const CertifiedAgent& lead = *sequences.front();
  res.rounds = lead.total_rounds();
  res.solve_stages = opened_solve_stages(lead.solves());
  res.restarts = lead.total_restarts();
  res.stop_reason = lead.solves().back().stop_reason;
  res.bytes_exchanged = stats.bytes;
  res.messages = stats.messages;
  res.longest_chain = stats.longest_chain;
  int offset = 0;
  for (const auto& stage : lead.solves()) {
    for (const auto& r : stage.trace) {
      DistributedRound row{offset + r.round, stage.rank, r.cost, r.grad_norm,
                           r.selected,       r.restart,  0,      r.elapsed_s};
      auto b = stats.bytes_per_stage_round.find({stage.stage, static_cast<std::uint32_t>(r.round)});
      if (b != stats.bytes_per_stage_round.end()) row.bytes = b->second;
      res.trace.push_back(std::move(row));
    }
    offset += stage.rounds;
    if (stage.refine) res.refine_rounds += stage.rounds;
  }
  for (std::size_t s = 0; s < stats.bytes_per_stage.size(); ++s) {
    const StageKind kind = stage_kind(static_cast<std::uint32_t>(s));
    if (kind == StageKind::kCertify) res.certificate_bytes += stats.bytes_per_stage[s];
    if (kind == StageKind::kEscape) res.escape_bytes += stats.bytes_per_stage[s];
  }
  res.certified = lead.certified();
  res.certificates = lead.certificates();
  res.escapes = lead.escapes();
  res.refines = lead.refines();
  if (!res.certificates.empty()) {
    const auto& c = res.certificates.back().result;
    res.min_eigenvalue = c.min_eigenvalue;
    res.certificate_tolerance = c.tolerance;
    res.certificate_residual = c.residual;
    res.certificate_bound = c.bound;
  }
  res.certificate_rounds = lead.certificate_iterations();
  res.escape_rounds = lead.escape_trials();
  res.final_rank = lead.final_rank();
  res.X.resize(res.final_rank, w * static_cast<Eigen::Index>(graph.num_poses));
  for (int b = 0; b < N; ++b)
    scatter_pose_columns(states[static_cast<std::size_t>(b)]->Y,
                         layout.poses[static_cast<std::size_t>(b)], graph.d, res.X);
  for (const auto& s : states) {
    res.block_updates += s->block_updates();
    res.tcg_iterations += s->tcg_iterations();
    res.tangent_updates += s->tangent_updates();
    res.tangent_factorizations += s->tangent_factorizations();
  }
  res.relaxation_cost = res.trace.empty() ? 0.0 : res.trace.back().cost;
  res.grad_norm = res.trace.empty() ? 0.0 : res.trace.back().grad_norm;
  if (options.round_result) {
    const auto rounding_start = Clock::now();
    res.poses = round_solution(graph, res.X);
    res.rounding_s = since(rounding_start);
    res.cost = evaluate_objective(graph, res.poses);
    res.certified = estimate_certified(res.certified, res.cost, res.relaxation_cost);
  }
  res.wall_s = since(start);
  return res;
}

long long message_steps(const DistributedResult& r) {
  return 2LL * r.rounds + 2LL * r.solve_stages + message_steps(r.refines);
}

}  // namespace tessera
