#include "agent/online_agent_summary.hpp"

#include <algorithm>
#include <cmath>

#include "online_options_json.hpp"

namespace tessera::agent {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

std::string online_summary_json(const OnlineAgentOptions& o, const OnlineSummaryState& state,
                                const OnlineFigures& f) {
  const GraphStream* g = state.graph;
  const SolveOutcome& final_solve = state.final_solve;
  cli::JsonObject j;
  j.add("agent", o.id).add("robots", o.robots).add("run_id", o.run_id);
  cli::add_online_solver_options(j, o.online);
  j.add("epochs", static_cast<long long>(state.epochs))
      .add("solves", f.solves)
      .add("rounds", f.rounds)
      .add("final_rounds", final_solve.rounds)
      .add("total_poses", g ? g->graph().num_poses : std::size_t{0})
      .add("total_measurements", g ? g->graph().measurements.size() : std::size_t{0})
      .add("bytes_sent", static_cast<long long>(f.bytes_sent))
      .add("messages_sent", static_cast<long long>(f.messages_sent))
      .add("report_bytes", static_cast<long long>(f.report_bytes))
      .add("idle_waits", static_cast<long long>(f.idle_waits))
      .add("cpu_s", f.cpu_s)
      .add("wall_s", state.wall_s)
      .add("latency_median_s", percentile(f.batch_latency_s, 0.5))
      .add("latency_p95_s", percentile(f.batch_latency_s, 0.95))
      .add("latency_cpu_median_s", percentile(f.batch_latency_cpu_s, 0.5))
      .add("latency_cpu_p95_s", percentile(f.batch_latency_cpu_s, 0.95))
      .add("certified", final_solve.certified)
      .add("min_eigenvalue", final_solve.min_eigenvalue)
      .add("grad_norm", final_solve.grad_norm);
  if (state.cost) j.add("cost", *state.cost);
  j.add("rebalance", cli::rebalance_options_json(o.online.rebalance))
      .add("final_blocks", state.final_blocks)
      .add("final_cut", state.final_cut);
  j.add("publications", f.publications);
  j.add("updates", f.updates);
  if (!f.certificates.empty()) j.add("certificates", f.certificates);
  if (!f.faults.empty()) j.add("faults", f.faults);
  return j.str();
}

}  // namespace tessera::agent
