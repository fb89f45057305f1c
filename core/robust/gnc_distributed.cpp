#include <algorithm>
#include <stdexcept>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>

namespace tessera {
namespace {

// Bytes of one agent's outer-step broadcast: its residual maximum and its weight spread (two
// doubles, to N - 1 agents) and, per cut measurement it owns, the index and the weight it
// sends to the other end.
std::uint64_t outer_step_bytes(const PoseGraph& graph, const std::vector<int>& assignment,
                               int agents) {
  std::uint64_t cut = 0;
  for (const auto& m : graph.measurements)
    if (assignment[m.i] != assignment[m.j]) ++cut;
  return static_cast<std::uint64_t>(agents) * static_cast<std::uint64_t>(agents - 1) * 16 +
         cut * 16;
}

// The lifted residual of m at X: the measurement's term of the relaxed objective,
// kappa ||Y_j - Y_i R_ij||_F^2 + tau ||p_j - p_i - Y_i t_ij||^2 (the rounded residual when X
// has rank d).
double lifted_residual_squared(const Measurement& m, const Eigen::MatrixXd& X, int d) {
  const Eigen::Index w = d + 1;
  const auto Xi = X.middleCols(w * static_cast<Eigen::Index>(m.i), w);
  const auto Xj = X.middleCols(w * static_cast<Eigen::Index>(m.j), w);
  const auto Yi = Xi.leftCols(d);
  return m.kappa * (Xj.leftCols(d) - Yi * m.R).squaredNorm() +
         m.tau * (Xj.col(d) - Xi.col(d) - Yi * m.t).squaredNorm();
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

double lifted_cost(const PoseGraph& graph, const Eigen::MatrixXd& X) {
  double f = 0;
  for (const Measurement& m : graph.measurements) f += lifted_residual_squared(m, X, graph.d);
  return f;
}

std::vector<std::size_t> zero_weight(const std::vector<double>& weights) {
  std::vector<std::size_t> out;
  for (std::size_t e = 0; e < weights.size(); ++e)
    if (weights[e] == 0) out.push_back(e);
  return out;
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

GncDistributedResult solve_gnc_distributed(const PoseGraph& graph,
                                           const std::vector<int>& assignment,
                                           const GncDistributedOptions& options) {
  options.validate();
  if (!options.known_inlier_flags.empty() &&
      options.known_inlier_flags.size() != graph.num_measurements())
    throw std::invalid_argument("solve_gnc_distributed: one known-inlier flag per measurement");
  GncDistributedResult out;
  const RobustOptions& robust = options.robust;
  // The candidates' count is one more integer in the first residual vote.
  std::vector<bool> known(graph.num_measurements());
  std::size_t candidates = 0;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    known[e] = is_known_inlier(graph.measurements[e], robust.known_inliers) ||
               (!options.known_inlier_flags.empty() && options.known_inlier_flags[e]);
    candidates += known[e] ? 0 : 1;
  }
  out.threshold_squared = tls_threshold_squared(robust, graph.d, candidates);
  const double c2 = out.threshold_squared;
  const int agents = *std::max_element(assignment.begin(), assignment.end()) + 1;
  const std::uint64_t vote_bytes = outer_step_bytes(graph, assignment, agents);

  DistributedOptions inner = options.solver;
  inner.certify = false;
  // The known inliers alone connect the poses (the usual case: odometry chains joined by
  // rendezvous links): then the start can come from them, and an edge whose weight is exactly
  // 0 can leave the weighted solves (it adds nothing to the cost; without it the block
  // adjacency graph has fewer colours, so more agents update per round).
  const PoseGraph known_graph = known_subgraph(graph, known);
  const bool known_connected = count_components(known_graph) <= 1;
  // Two candidate starts: the known inliers' initialization (it does not see the wrong
  // closures, but drifts) and the solver's own (chordal fits every closure, wrong ones too;
  // on clean data it is nearly the optimum). The one with the lower TLS cost (the robust
  // objective: every rejectable term capped at c^2; a sum over the weight owners, one scalar
  // vote each) is taken. Clean files then start where the plain solve starts, contaminated
  // ones from the odometry.
  const int robots = inner.robots > 0 ? inner.robots : agents;
  std::vector<Pose> start = initial_poses(graph, inner.initialization, robots);
  if (options.known_inlier_start && known_connected) {
    std::vector<Pose> chains = distributed_initialization(known_graph, robots);
    if (tls_cost(graph, known, chains, c2) < tls_cost(graph, known, start, c2))
      start = std::move(chains);
    out.total_bytes += vote_bytes;
  }
  // Every solve before the final one is capped: GNC needs only a rough minimiser between two
  // weight updates, and the first (plain) solve only has to tell the wrong closures' residuals
  // from the right ones'. Misjudged measurements are re-admitted at the end.
  if (robust.inner_max_rounds > 0)
    inner.max_rounds = std::min(inner.max_rounds, robust.inner_max_rounds);
  DistributedResult solve = solve_distributed(graph, assignment, inner, start);
  out.total_rounds += solve.rounds;
  out.total_bytes += solve.bytes_exchanged;

  // Every agent reports its residual maximum; all take the same max (agent-id order).
  double max_r2 = 0;
  for (int a = 0; a < agents; ++a)
    max_r2 = std::max(max_r2, agent_weights(a, graph, assignment, solve.X, robust, c2, 0,
                                            options.known_inlier_flags)
                                  .max_residual_squared);
  out.total_bytes += vote_bytes;
  out.weights.assign(graph.num_measurements(), 1.0);
  double mu = gnc_initial_mu(max_r2, c2);
  out.weights_converged = mu == 0;
  while (!out.weights_converged && out.outer_iterations < robust.max_outer_iterations) {
    double spread = 0;
    for (int a = 0; a < agents; ++a) {
      const AgentWeights mine =
          agent_weights(a, graph, assignment, solve.X, robust, c2, mu, options.known_inlier_flags);
      for (std::size_t k = 0; k < mine.measurements.size(); ++k)
        out.weights[mine.measurements[k]] = mine.weights[k];
      spread += mine.weight_spread;
    }
    PoseGraph weighted = weighted_graph(graph, out.weights, {});
    if (known_connected) weighted = inlier_graph(weighted, zero_weight(out.weights), {});
    solve = solve_distributed_from_lifted(weighted, assignment, inner, solve.X);
    out.total_rounds += solve.rounds;
    out.total_bytes += solve.bytes_exchanged + vote_bytes;
    ++out.outer_iterations;
    out.weights_converged = spread <= robust.weight_tolerance;
    mu *= robust.mu_step;
  }

  for (std::size_t e = 0; e < out.weights.size(); ++e)
    if (out.weights[e] < 0.5) out.rejected.push_back(e);
  // The final solve of the inlier set, to the solver's tolerance. A rejected measurement whose
  // residual at that solution is within the bound (r^2 <= c^2: TLS would count it as an
  // inlier there) was misjudged on a rough iterate and is taken back, then the set is solved
  // again; each weight owner checks its own rejected measurements (a vote per agent).
  // Re-admission runs on uncertified solves (the staircase may raise the rank, which a further
  // solve could not start from); the certificate is taken once, on the set that stays.
  DistributedOptions full = options.solver;
  full.certify = false;
  for (int pass = 0;; ++pass) {
    const PoseGraph inliers = inlier_graph(graph, out.rejected, {});
    require_connected_inliers(graph, inliers, out.rejected.size());
    Eigen::MatrixXd X0 = solve.X;
    if (pass == 0) {
      // The capped solves leave the slow, long-range part of the error behind; on the inlier
      // set (no wrong closures left) the solver's own initialization is usually far closer to
      // the optimum. Both costs are a sum over the agents (one more scalar vote): the better
      // start wins.
      Eigen::MatrixXd guess =
          lift_poses(initial_poses(inliers, options.solver.initialization,
                                   options.solver.robots > 0 ? options.solver.robots : agents),
                     static_cast<int>(X0.rows()));
      if (lifted_cost(inliers, guess) < lifted_cost(inliers, X0)) X0 = std::move(guess);
      out.total_bytes += vote_bytes;
    }
    solve = solve_distributed_from_lifted(inliers, assignment, full, X0);
    out.total_rounds += solve.rounds;
    out.total_bytes += solve.bytes_exchanged;
    if (pass == robust.readmission_passes || out.rejected.empty()) break;
    std::vector<std::size_t> still;
    for (std::size_t e : out.rejected)
      if (lifted_residual_squared(graph.measurements[e], solve.X, graph.d) <= c2)
        out.weights[e] = 1.0;
      else
        still.push_back(e);
    out.total_bytes += vote_bytes;
    if (still.size() == out.rejected.size()) break;
    out.readmitted += out.rejected.size() - still.size();
    out.rejected = std::move(still);
  }
  if (options.solver.certify) {
    out.final_solve = solve_distributed_from_lifted(inlier_graph(graph, out.rejected, {}),
                                                    assignment, options.solver, solve.X);
    out.total_rounds += out.final_solve.rounds;
    out.total_bytes += out.final_solve.bytes_exchanged;
  } else {
    out.final_solve = std::move(solve);
  }
  return out;
}

}  // namespace tessera
