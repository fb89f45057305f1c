#include <algorithm>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>

#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_solve_setup.hpp"

namespace tessera {
namespace {

// The lifted residual of m at X (global order): the measurement's term of the relaxed
// objective (the rounded residual when X has rank d).
double lifted_residual_squared(const Measurement& m, const Eigen::MatrixXd& X, int d) {
  const Eigen::Index w = d + 1;
  return lifted_residual_squared(m, X.middleCols(w * static_cast<Eigen::Index>(m.i), w),
                                 X.middleCols(w * static_cast<Eigen::Index>(m.j), w));
}

}  // namespace

void GncDistributedOptions::validate() const {
  solver.validate();
  robust.validate();
  if (cluster_probes < 0)
    throw InputError("GncDistributedOptions.cluster_probes = " + std::to_string(cluster_probes) +
                     ": must be >= 0 (0 = none)");
  clusters.validate();
}

int weight_owner(const Measurement& m, const std::vector<int>& assignment) {
  return assignment[std::min(m.i, m.j)];
}

AgentWeights agent_weights(int agent, const PoseGraph& graph, const std::vector<int>& assignment,
                           const Eigen::MatrixXd& X, const RobustOptions& robust, double c2,
                           double mu, const std::vector<bool>& flags) {
  AgentWeights out;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    const Measurement& m = graph.measurements[e];
    if (weight_owner(m, assignment) != agent) continue;
    double w = 1.0;
    if (!is_known_inlier(m, robust.known_inliers) && (flags.empty() || !flags[e])) {
      const double r2 = lifted_residual_squared(m, X, graph.d);
      out.max_residual_squared = std::max(out.max_residual_squared, r2);
      if (mu > 0) w = tls_weight(r2, c2, mu);
    }
    out.measurements.push_back(e);
    out.weights.push_back(w);
    out.weight_spread += w * (1 - w);
  }
  return out;
}

std::optional<std::vector<Pose>> known_inlier_poses(const PoseGraph& graph,
                                                    const GncDistributedOptions& options,
                                                    int agents) {
  if (!options.known_inlier_start) return std::nullopt;
  std::vector<bool> known(graph.num_measurements());
  for (std::size_t e = 0; e < graph.num_measurements(); ++e)
    known[e] = is_known_inlier(graph.measurements[e], options.robust.known_inliers) ||
               (!options.known_inlier_flags.empty() && options.known_inlier_flags[e]);
  const PoseGraph known_graph = known_subgraph(graph, known);
  if (count_components(known_graph) > 1) return std::nullopt;
  const int robots = options.solver.robots > 0 ? options.solver.robots : agents;
  return distributed_initialization(known_graph, robots);
}

GncDistributedResult solve_gnc_distributed(const PoseGraph& graph,
                                           const std::vector<int>& assignment,
                                           const GncDistributedOptions& run_options) {
  run_options.validate();
  // The agents' refinements keep their factors' analyses from one solve to the next
  // (NewtonRefineOptions::analyses; the agents hold these options by reference).
  GncDistributedOptions options = run_options;
  if (!options.solver.refine.analyses)
    options.solver.refine.analyses = make_interface_analysis_store();
  if (!options.known_inlier_flags.empty() &&
      options.known_inlier_flags.size() != graph.num_measurements())
    throw std::invalid_argument("solve_gnc_distributed: one known-inlier flag per measurement");
  const DistributedOptions& solver = options.solver;
  if (solver.rank < graph.d)
    throw InputError("DistributedOptions.rank must be >= d = " + std::to_string(graph.d));
  const BlockLayout layout = make_block_layout(graph.num_poses, graph.measurements, assignment);
  const int agents = layout.num_blocks;
  const int robots = solver.robots > 0 ? solver.robots : agents;
  const Eigen::MatrixXd X0 =
      lift_poses(initial_poses(graph, solver.initialization, robots), solver.rank);
  const std::optional<std::vector<Pose>> known = known_inlier_poses(graph, options, agents);
  const Eigen::MatrixXd X0_known = known ? lift_poses(*known, solver.rank) : Eigen::MatrixXd();
  const Eigen::Index w = graph.d + 1;

  // Every agent gets what a DDS agent holds after the hand-off: the endpoints of the whole
  // graph, the measurements touching its poses and its block of the starting point.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  structure.reserve(graph.num_measurements());
  for (const auto& m : graph.measurements)
    structure.emplace_back(static_cast<std::uint32_t>(m.i), static_cast<std::uint32_t>(m.j));
  std::vector<std::unique_ptr<GncAgent>> gnc;
  std::vector<AgentProcess*> processes;
  for (int b = 0; b < agents; ++b) {
    GncAgentInput in;
    in.id = b;
    in.num_agents = agents;
    in.d = graph.d;
    in.num_poses = graph.num_poses;
    in.owner = assignment;
    in.structure = structure;
    in.known_inlier = options.known_inlier_flags;
    for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
      const Measurement& m = graph.measurements[e];
      if (assignment[m.i] != b && assignment[m.j] != b) continue;
      in.measurements.push_back(m);
      in.measurement_index.push_back(e);
    }
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    in.Y0 = gather_pose_columns(X0, ids, graph.d);
    if (known) in.Y0_known = gather_pose_columns(X0_known, ids, graph.d);
    in.kept_set_start = options.kept_set_start;
    in.initialization = solver.initialization;
    in.source = graph.source;
    in.pcm = options.robust.kind == RobustKind::kPcmGnc;
    // Without the final certified solve: it runs below, for its full record.
    gnc.push_back(std::make_unique<GncAgent>(std::move(in), options, false));
    if (options.weight_observer)
      gnc.back()->set_weight_observer([&options, b](int outer,
                                                    const std::vector<std::uint64_t>& index,
                                                    const std::vector<double>& weights) {
        options.weight_observer(b, outer, index, weights);
      });
    processes.push_back(gnc.back().get());
  }
  const DeliveryStats stats = run_in_process(processes, solver.delivery, solver.delivery_seed);

  GncDistributedResult out;
  const GncAgent& lead = *gnc.front();
  static_cast<GncAgentResult&>(out) = lead.result();
  out.late_rejected = lead.late_rejected();
  out.weights.assign(graph.num_measurements(), 1.0);
  // Each measurement's weight as its owner computed it.
  for (int b = 0; b < agents; ++b) {
    const GncAgent& a = *gnc[static_cast<std::size_t>(b)];
    const auto& index = a.measurement_index();
    for (std::size_t k = 0; k < index.size(); ++k)
      if (weight_owner(graph.measurements[index[k]], assignment) == b)
        out.weights[index[k]] = a.weights()[k];
  }
  out.total_rounds = lead.gnc_rounds();
  out.total_bytes = stats.bytes;
  out.longest_chain = stats.longest_chain;

  // The last solve of the kept set with its full record (trace, certificate, refinement): when
  // the agents run a final solve (certification or RobustOptions::final_refine) that one, from
  // the agents' iterate; without, the agents' last inlier pass again from its start (the same
  // arithmetic, so the same iterate).
  const PoseGraph inliers = inlier_graph(graph, out.rejected, {});
  const bool final_runs = lead.final_solve_runs();
  Eigen::MatrixXd X(solver.rank, w * static_cast<Eigen::Index>(graph.num_poses));
  for (int b = 0; b < agents; ++b) {
    const GncAgent& a = *gnc[static_cast<std::size_t>(b)];
    scatter_pose_columns(final_runs ? a.state().Y : a.last_pass_start(),
                         layout.poses[static_cast<std::size_t>(b)], graph.d, X);
  }
  DistributedOptions last = solver;
  // The refinement as the agents' own solve of that kind had it.
  last.refine = gnc_solve_options(
                    options, final_runs ? GncSolveKind::kFinal : GncSolveKind::kInlierPass, false)
                    .refine;
  // Where the agents' final solve would start at its refinement, so does this one.
  out.final_solve = solve_distributed_from_lifted(
      inliers, assignment, last, X,
      final_runs ? lead.final_start_grad_norm() : std::numeric_limits<double>::quiet_NaN());
  if (final_runs) {
    out.total_rounds += out.final_solve.rounds;
    out.final_refine_message_steps = message_steps(out.final_solve.refines);
    out.final_solve_stages = out.final_solve.solve_stages;
    out.total_bytes += out.final_solve.bytes_exchanged;
    out.longest_chain += out.final_solve.longest_chain;
  }
  return out;
}

long long message_steps(const GncDistributedResult& r) {
  return message_steps(r, r.total_rounds, r.final_solve_stages, r.final_refine_message_steps);
}

}  // namespace tessera
