#include "runtime/gnc_round_loop.hpp"

#include <chrono>
#include <string>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/robust/gnc_agent.hpp>

#include "runtime/round_finish.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {

RoundLoopResult run_gnc_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                                   double receive_timeout_s) {
  GncDistributedOptions options;
  options.solver = distributed_options_of(local.options);
  options.robust = local.options.robust;
  options.known_inlier_start = local.options.gnc_known_start;
  options.cluster_probes = local.options.gnc_cluster_probes;
  // The refinements keep their factors' analyses from one solve to the next.
  options.solver.refine.analyses = make_interface_analysis_store();
  if (options.solver.rank < local.d)
    throw std::runtime_error("rank " + std::to_string(options.solver.rank) +
                             " is below d = " + std::to_string(local.d));
  if (local.initial.size() != local.owned.size())
    throw std::runtime_error("agent " + std::to_string(local.agent_id) + ": " +
                             std::to_string(local.initial.size()) + " initial poses for " +
                             std::to_string(local.owned.size()) + " owned poses");

  GncAgentInput in;
  in.id = static_cast<int>(local.agent_id);
  in.num_agents = static_cast<int>(local.num_agents);
  in.d = local.d;
  in.num_poses = local.num_poses;
  in.owner.assign(local.owner.begin(), local.owner.end());
  in.structure = local.structure;
  in.measurements = local.measurements;
  in.measurement_index = local.measurement_index;
  in.known_inlier = local.known_inlier;
  in.pcm = local.options.robust.kind == RobustKind::kPcmGnc;
  in.Y0 = lift_poses(local.initial, options.solver.rank);
  if (!local.known_initial.empty())
    in.Y0_known = lift_poses(local.known_initial, options.solver.rank);
  in.kept_set_start = options.kept_set_start;
  // The run's initialization (the kept set's fresh start uses the same).
  in.initialization = local.options.initialization.empty()
                          ? DistributedOptions{}.initialization
                          : parse_init(local.options.initialization);
  GncAgent agent(std::move(in), options, true);

  Mailbox mail(channel, receive_timeout_s, local.agent_id);
  mail.set_num_agents(local.num_agents);
  const auto t0 = std::chrono::steady_clock::now();
  mail.run_protocol(agent, agent.start(), [&] {
    return "outer step " + std::to_string(agent.outer_iterations()) + " of the robust solve";
  });

  // The last solve of the kept set: the final one when it ran (certification or
  // RobustOptions::final_refine), else the last inlier pass.
  const CertifiedAgent& last = agent.last_solve();
  RoundLoopResult res;
  res.rounds = static_cast<std::uint32_t>(agent.total_rounds());
  res.restarts = static_cast<std::uint32_t>(last.total_restarts());
  res.stop_reason = last.solves().back().stop_reason;
  if (!last.solves().back().trace.empty()) {
    res.relaxation_cost = last.solves().back().trace.back().cost;
    res.grad_norm = last.solves().back().trace.back().grad_norm;
  }
  const bool certified_sequence = agent.final_sequence() != nullptr && options.solver.certify;
  if (certified_sequence) {
    res.certified = last.certified();
    if (!last.certificates().empty())
      res.min_eigenvalue = last.certificates().back().result.min_eigenvalue;
    res.certificate_rounds = static_cast<std::uint32_t>(last.certificate_iterations());
    res.escape_rounds = static_cast<std::uint32_t>(last.escape_trials());
  }
  res.final_rank = static_cast<std::uint32_t>(agent.state().rank());
  RobustRunReport report;
  static_cast<GncAgentResult&>(report) = agent.result();
  if (const CertifiedAgent* final_solve = agent.final_sequence()) {
    report.final_refine_steps = message_steps(final_solve->refines());
    report.final_solve_stages = opened_solve_stages(final_solve->solves());
  }
  res.robust = std::move(report);

  // The rounding sees the kept measurements (the cost is over them).
  AgentLocalData kept = local;
  kept.measurements = agent.kept_measurements();
  kept.measurement_index = agent.kept_index();
  return round_and_report(kept, agent.layout(), agent.state(), mail, channel, std::move(res),
                          certified_sequence, t0);
}

}  // namespace tessera::agent
