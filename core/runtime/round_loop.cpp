#include "runtime/round_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <tessera/certification/certificate_cap.hpp>
#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/coarse_exchange.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>

#include "runtime/coarse_space_share.hpp"
#include "runtime/gnc_round_loop.hpp"
#include "runtime/round_finish.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {

namespace {

// 1, 2, 5, 10, 20, 50, ...: a few memory lines however long the solve runs.
bool worth_a_memory_line(std::size_t round) {
  while (round >= 10 && round % 10 == 0) round /= 10;
  return round == 1 || round == 2 || round == 5;
}

}  // namespace

DistributedOptions distributed_options_of(const RunOptions& o) {
  DistributedOptions opt;
  if (!o.algorithm.empty()) opt.algorithm = parse_algorithm(o.algorithm);
  if (o.rank > 0) opt.rank = static_cast<int>(o.rank);
  if (o.max_rounds > 0) opt.max_rounds = static_cast<int>(o.max_rounds);
  if (o.grad_norm_tolerance > 0) opt.grad_norm_tol = o.grad_norm_tolerance;
  opt.rel_cost_decrease_tol = o.relative_cost_tolerance;
  opt.seed = o.seed;
  opt.certify = o.certify;
  opt.staircase.certificate.max_iterations = kCommandCertificateIterations;
  opt.coarse.enabled = o.coarse_every > 0;
  if (o.coarse_every > 0) opt.coarse.every = static_cast<int>(o.coarse_every);
  if (o.coarse_aggregates > 0) {
    opt.coarse.space = CoarseSpaceKind::kSmoothed;
    opt.coarse.aggregates = static_cast<int>(o.coarse_aggregates);
    opt.coarse.smoothing_steps = static_cast<int>(o.coarse_smoothing);
  }
  set_refine_mode(opt.refine, o.refine);
  if (o.refine_grad_tol > 0) opt.refine.grad_norm_tol = o.refine_grad_tol;
  if (o.refine_rel_tol > 0) opt.refine.relative_decrease_tol = o.refine_rel_tol;
  if (!o.refine_sigma.empty())
    set_sigma_mode(opt.refine, o.refine_sigma, "RunOptions::refine_sigma");
  if (o.max_factor_entries > 0)
    opt.block_update.max_factor_entries = static_cast<std::size_t>(o.max_factor_entries);
  opt.block_update.tangent_split_dots = o.tangent_split_dots;
  opt.validate();
  return opt;
}

void ProtocolChannel::send_all(const std::vector<OutgoingMessage>& messages) {
  for (const auto& m : messages) send(m);
}

void ProtocolChannel::report(const AgentReport& /*report*/) {}

std::optional<ProtocolMessage> ProtocolChannel::receive_after(double timeout_s,
                                                              std::size_t /*wake_after*/) {
  return receive(timeout_s);
}

std::optional<ProtocolMessage> ProtocolChannel::receive_awaiting(double timeout_s,
                                                                 const AwaitedMessages& awaited) {
  return receive_after(timeout_s, awaited.senders.size());
}

RoundLoopResult run_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                               double receive_timeout_s, const RoundLoopHooks& hooks) {
  if (local.options.robust.kind != RobustKind::kNone) {
    if (hooks.resume_from)
      throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                               ": a robust run cannot resume from a checkpoint");
    return run_gnc_round_loop(local, channel, receive_timeout_s);
  }
  const DistributedOptions options = distributed_options_of(local.options);
  const bool lifted = local.lifted_start.size() > 0;
  if (lifted &&
      (local.lifted_start.cols() != (local.d + 1) * static_cast<Eigen::Index>(local.owned.size()) ||
       local.lifted_start.rows() != options.rank))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": lifted starting point of the wrong shape");
  if (!lifted && local.initial.size() != local.owned.size())
    throw std::runtime_error("agent " + std::to_string(local.agent_id) + ": " +
                             std::to_string(local.initial.size()) + " initial poses for " +
                             std::to_string(local.owned.size()) +
                             " owned poses (run the initialisation stage first)");
  if (options.rank < local.d)
    throw std::runtime_error("rank " + std::to_string(options.rank) +
                             " is below d = " + std::to_string(local.d));

  // Every agent builds the same layout from the structure (endpoints only, 8 bytes a
  // measurement of the whole graph: no Measurement copies, which held 72). The layout and
  // the coarse spaces take the owners as int; one conversion serves them all.
  const std::vector<int> owner(local.owner.begin(), local.owner.end());
  const BlockLayout layout = make_block_layout(local.num_poses, local.structure, owner);
  const auto phase = [&](const std::string& name) {
    if (hooks.on_phase) hooks.on_phase(name);
  };
  phase("block layout");
  const auto& own = layout.poses[local.agent_id];
  if (own.size() != local.owned.size() || !std::equal(own.begin(), own.end(), local.owned.begin()))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": owned poses do not match the assignment");

  // Core's agent, configured as the in-process engine configures it.
  // Its block-update options too: they carry the factor cap (a large team's shared one,
  // runtime/team_memory.hpp), which the constructor applies when it factors.
  AgentState state(static_cast<int>(local.agent_id), local.d, layout, local.measurements,
                   lifted ? local.lifted_start : lift_poses(local.initial, options.rank),
                   options.block_update);
  phase("block state");
  if (options.coarse.enabled && options.coarse.space == CoarseSpaceKind::kSmoothed) {
    // Every agent builds the same space from the structure (no message needed) and keeps the
    // part it reads.
    CoarseSpace built = make_coarse_space(local.num_poses, local.structure, owner, options.coarse);
    if (static_cast<int>(local.agent_id) != kCoarseSolver)
      keep_agent_share(built, layout, static_cast<int>(local.agent_id), local.measurements);
    auto space = std::make_shared<const CoarseSpace>(std::move(built));
    const std::size_t space_bytes = space->bytes();
    state.use_coarse_space(std::move(space), local.measurements);
    // Its two parts by what they grow with (docs/scale.md, "The memory model").
    char sizes[96];
    std::snprintf(sizes, sizeof(sizes), " (the space %.1f MB, the block's terms %.1f MB)",
                  static_cast<double>(space_bytes) / 1048576.0,
                  static_cast<double>(state.smoothed_coarse_bytes()) / 1048576.0);
    phase(std::string("smoothed coarse space") + sizes);
  }
  if (options.refine.enabled && options.refine.coarse == NewtonRefineOptions::Coarse::kSmoothed)
    state.use_refine_space(std::make_shared<const CoarseSpace>(make_coarse_space(
        local.num_poses, local.structure, owner, options.refine.coarse_space_options())));
  if (hooks.after_set_up) hooks.after_set_up();
  phase("block set-up");
  // The rounds' memory lines, from whichever protocol runs below.
  // The count can move by more than one round between two handled messages, so a line is due
  // when a round worth one was passed.
  std::size_t last_round_seen = 0;
  const auto round_phase = [&](std::size_t rounds) {
    if (!hooks.on_phase || rounds <= last_round_seen) return;
    bool due = false;
    for (std::size_t r = last_round_seen + 1; r <= rounds && !due; ++r)
      due = worth_a_memory_line(r);
    last_round_seen = rounds;
    if (due) phase("round " + std::to_string(rounds));
  };
  const double variables =
      static_cast<double>(options.rank) * (local.d + 1) * static_cast<double>(local.num_poses);
  const auto scheme = make_momentum_scheme(options, layout, variables);
  const RoundConfig config = make_round_config(options, scheme.get());
  Mailbox mail(channel, receive_timeout_s, local.agent_id);
  mail.set_num_agents(local.num_agents);
  mail.on_progress_point = hooks.on_progress_point;
  RoundLoopResult res;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<CertifiedAgent> sequence;
  if (!options.certify && !options.refine.enabled) {
    RoundProtocol protocol(state, layout, config);
    if (hooks.on_round) protocol.set_round_observer(hooks.on_round);
    if (hooks.on_phase)
      mail.after_handled = [&] { round_phase(static_cast<std::size_t>(protocol.rounds())); };
    mail.run_protocol(
        protocol, hooks.resume_from ? protocol.resume(*hooks.resume_from) : protocol.start(),
        [&] { return "round " + std::to_string(protocol.rounds()) + " of the solve"; });
    mail.after_handled = nullptr;
    res.rounds = static_cast<std::uint32_t>(protocol.rounds());
    res.restarts = static_cast<std::uint32_t>(protocol.restarts());
    res.stop_reason = protocol.stop_reason();
    if (!protocol.trace().empty()) {
      res.relaxation_cost = protocol.trace().back().cost;
      res.grad_norm = protocol.trace().back().grad_norm;
    }
  } else {
    // The certified sequence. Checkpoints and rollbacks cover its first solve stage.
    sequence = std::make_unique<CertifiedAgent>(state, layout, options);
    if (hooks.on_round) sequence->set_round_observer(hooks.on_round);
    // The stage kind on the agent now (0 rounds, 1 refinement, 2 certificate) and since when.
    int timed_stage = 0;
    double stage_since = 0.0, stage_wait = 0.0;
    const auto close_stage = [&](int next) {
      const double now =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (timed_stage == 1) {
        res.refine_wall_s += now - stage_since;
        res.refine_wait_s += mail.wait_s - stage_wait;
      } else if (timed_stage == 2) {
        res.certificate_wall_s += now - stage_since;
        res.certificate_wait_s += mail.wait_s - stage_wait;
      }
      timed_stage = next;
      stage_since = now;
      stage_wait = mail.wait_s;
    };
    mail.after_handled = [&] {
      const int now_stage = sequence->refining() ? 1 : sequence->certificate_progress() ? 2 : 0;
      if (now_stage != timed_stage) close_stage(now_stage);
      round_phase(static_cast<std::size_t>(sequence->rounds_so_far()));
      const auto p = sequence->certificate_progress();
      if (p && p->first > 0)  // from its first iteration on: a lambda_min estimate to show
        mail.report_progress(ProgressStage::kCertificate, p->first, p->second);
      else if (p && mail.on_progress_point)  // nothing to show yet, but a point all the same
        mail.on_progress_point(ProgressStage::kCertificate);
      else if (const auto r = sequence->refine_progress())
        mail.report_progress(ProgressStage::kRefinement,
                             refinement_iteration(r->step, r->cg_iteration), r->grad_norm);
    };
    mail.run_protocol(
        *sequence, hooks.resume_from ? sequence->resume(*hooks.resume_from) : sequence->start(),
        [&] { return "stage " + std::to_string(sequence->stage()) + " of the certified solve"; });
    close_stage(0);
    res.refines = sequence->refines();
    const SolveStageRecord& last = sequence->solves().back();
    res.rounds = static_cast<std::uint32_t>(sequence->total_rounds());
    res.restarts = static_cast<std::uint32_t>(sequence->total_restarts());
    res.stop_reason = last.stop_reason;
    if (!last.trace.empty()) {
      res.relaxation_cost = last.trace.back().cost;
      res.grad_norm = last.trace.back().grad_norm;
    }
    if (options.certify) res.certified = sequence->certified();
    if (!sequence->certificates().empty()) {
      res.min_eigenvalue = sequence->certificates().back().result.min_eigenvalue;
      res.certificate_bound = sequence->certificates().back().result.bound;
    }
    res.certificate_rounds = static_cast<std::uint32_t>(sequence->certificate_iterations());
    res.escape_rounds = static_cast<std::uint32_t>(sequence->escape_trials());
    mail.after_handled = nullptr;
  }
  phase("rounds");
  res.final_rank = static_cast<std::uint32_t>(state.rank());
  return round_and_report(local, layout, state, mail, channel, std::move(res), options.certify, t0);
}

}  // namespace tessera::agent
