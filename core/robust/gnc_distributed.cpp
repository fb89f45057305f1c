#include <algorithm>
#include <memory>
#include <stdexcept>
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

namespace tessera {
namespace {

// The lifted residual of m at X (global order): the measurement's term of the relaxed
// objective (the rounded residual when X has rank d).
double lifted_residual_squared(const Measurement& m, const Eigen::MatrixXd& X, int d) {
  const Eigen::Index w = d + 1;
  return lifted_residual_squared(m, X.middleCols(w * static_cast<Eigen::Index>(m.i), w),
                                 X.middleCols(w * static_cast<Eigen::Index>(m.j), w));
}

// `graph` with only the measurements flagged in `known`.
PoseGraph known_subgraph(const PoseGraph& graph, const std::vector<bool>& known) {
  PoseGraph out;
  out.d = graph.d;
  out.num_poses = graph.num_poses;
  out.source = graph.source;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e)
    if (known[e]) out.measurements.push_back(graph.measurements[e]);
  return out;
}

// sum over measurements of r^2 (known inliers) or min(r^2, c^2) (the others) at `poses`.
double tls_cost(const PoseGraph& graph, const std::vector<bool>& known,
                const std::vector<Pose>& poses, double c2) {
  double f = 0;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    const Measurement& m = graph.measurements[e];
    const double r2 = residual_squared(m, poses[m.i], poses[m.j]);
    f += known[e] ? r2 : std::min(r2, c2);
  }
  return f;
}

}  // namespace

void GncDistributedOptions::validate() const {
  solver.validate();
  robust.validate();
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

std::vector<Pose> gnc_start(const PoseGraph& graph, const GncDistributedOptions& options,
                            int agents) {
  const DistributedOptions& solver = options.solver;
  const int robots = solver.robots > 0 ? solver.robots : agents;
  std::vector<Pose> start = initial_poses(graph, solver.initialization, robots);
  if (!options.known_inlier_start) return start;
  std::vector<bool> known(graph.num_measurements());
  std::size_t candidates = 0;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    known[e] = is_known_inlier(graph.measurements[e], options.robust.known_inliers) ||
               (!options.known_inlier_flags.empty() && options.known_inlier_flags[e]);
    candidates += known[e] ? 0 : 1;
  }
  // Two candidate starts: the known inliers' initialization (it does not see the wrong
  // closures, but drifts) and the solver's own (chordal fits every closure, wrong ones too; on
  // clean data it is nearly the optimum). The one with the lower TLS cost (every rejectable term
  // capped at c^2) is taken: clean files start where the plain solve starts, contaminated ones
  // from the odometry.
  const PoseGraph known_graph = known_subgraph(graph, known);
  if (count_components(known_graph) > 1) return start;
  std::vector<Pose> chains = distributed_initialization(known_graph, robots);
  if (!options.start_vote) return chains;
  const double c2 = tls_threshold_squared(options.robust, graph.d, candidates);
  if (tls_cost(graph, known, chains, c2) < tls_cost(graph, known, start, c2))
    start = std::move(chains);
  return start;
}

GncDistributedResult solve_gnc_distributed(const PoseGraph& graph,
                                           const std::vector<int>& assignment,
                                           const GncDistributedOptions& options) {
  options.validate();
  if (!options.known_inlier_flags.empty() &&
      options.known_inlier_flags.size() != graph.num_measurements())
    throw std::invalid_argument("solve_gnc_distributed: one known-inlier flag per measurement");
  const DistributedOptions& solver = options.solver;
  if (solver.rank < graph.d)
    throw InputError("DistributedOptions.rank must be >= d = " + std::to_string(graph.d));
  const BlockLayout layout = make_block_layout(graph.num_poses, graph.measurements, assignment);
  const int agents = layout.num_blocks;
  const Eigen::MatrixXd X0 = lift_poses(gnc_start(graph, options, agents), solver.rank);
  const Eigen::Index w = graph.d + 1;
  auto block_of = [&](const Eigen::MatrixXd& X, int b) {
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    Eigen::MatrixXd Y(X.rows(), w * static_cast<Eigen::Index>(ids.size()));
    for (std::size_t s = 0; s < ids.size(); ++s)
      Y.middleCols(w * static_cast<Eigen::Index>(s), w) =
          X.middleCols(w * static_cast<Eigen::Index>(ids[s]), w);
    return Y;
  };

  // Every agent gets what a DDS agent holds after the hand-off: the endpoints of the whole
  // graph, the measurements touching its poses and its block of the starting point.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  structure.reserve(graph.num_measurements());
  for (const auto& m : graph.measurements)
    structure.emplace_back(static_cast<std::uint32_t>(m.i), static_cast<std::uint32_t>(m.j));
  std::vector<std::unique_ptr<GncAgent>> gnc;
  std::vector<AgentProcess*> processes;
  std::unique_ptr<Eigen::MatrixXd> inlier_guess;
  std::vector<std::uint64_t> inlier_guess_for;
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
    in.Y0 = block_of(X0, b);
    // The first inlier pass may start from the solver's own initialization of the kept set
    // (computed once, for every agent), when its cost is lower (the agents' vote).
    if (options.inlier_set_start)
      in.inlier_start = [&, b](const std::vector<std::uint64_t>& rejected, int rank) {
        if (!inlier_guess || inlier_guess_for != rejected) {
          const std::vector<std::size_t> r(rejected.begin(), rejected.end());
          inlier_guess = std::make_unique<Eigen::MatrixXd>(
              lift_poses(initial_poses(inlier_graph(graph, r, {}), solver.initialization,
                                       solver.robots > 0 ? solver.robots : agents),
                         rank));
          inlier_guess_for = rejected;
        }
        return block_of(*inlier_guess, b);
      };
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
  out.outer_iterations = lead.outer_iterations();
  out.weights_converged = lead.weights_converged();
  out.threshold_squared = lead.threshold_squared();
  out.readmitted = lead.readmitted();
  out.late_rejected = lead.late_rejected();
  out.rejected.assign(lead.rejected().begin(), lead.rejected().end());
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

  // The last solve of the kept set with its full record (trace, certificate): with
  // certification the certified solve from the agents' iterate; without, the agents' last
  // inlier pass again from its start (the same arithmetic, so the same iterate).
  const PoseGraph inliers = inlier_graph(graph, out.rejected, {});
  const bool certify = solver.certify;
  Eigen::MatrixXd X(solver.rank, w * static_cast<Eigen::Index>(graph.num_poses));
  for (int b = 0; b < agents; ++b) {
    const GncAgent& a = *gnc[static_cast<std::size_t>(b)];
    const Eigen::MatrixXd& Y = certify ? a.state().Y : a.last_pass_start();
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    for (std::size_t s = 0; s < ids.size(); ++s)
      X.middleCols(w * static_cast<Eigen::Index>(ids[s]), w) =
          Y.middleCols(w * static_cast<Eigen::Index>(s), w);
  }
  DistributedOptions last = solver;
  last.certify = certify;
  out.final_solve = solve_distributed_from_lifted(inliers, assignment, last, X);
  if (certify) {
    out.total_rounds += out.final_solve.rounds;
    out.total_bytes += out.final_solve.bytes_exchanged;
  }
  return out;
}

}  // namespace tessera
