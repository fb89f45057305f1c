#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/pairwise_consistency.hpp>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/util/input_error.hpp>

#include "robust/cluster_probes.hpp"
#include "robust/swap_probe.hpp"

namespace tessera {
namespace {

std::vector<double> residuals(const PoseGraph& graph, const std::vector<Pose>& poses) {
  std::vector<double> r2(graph.num_measurements());
  for (std::size_t e = 0; e < r2.size(); ++e) {
    const Measurement& m = graph.measurements[e];
    r2[e] = residual_squared(m, poses[m.i], poses[m.j]);
  }
  return r2;
}

// A solve's problem with what its preconditioner's selection ranks by: each measurement's
// weight and whether it is a known inlier.
struct SolveInput {
  PoseGraph graph;
  std::vector<double> weights;
  std::vector<bool> known;
};

// Solves `in` with a preconditioner on the measurements select_preconditioner_edges keeps (the
// known inliers, then by weight within the flop budget), and books the solve's work. Without
// connected known inliers nothing guarantees that a subset holds the poses together, so the
// preconditioner keeps every measurement.
CentralizedResult run_solve(const SolveInput& in, const CentralizedOptions& solver,
                            const PreconditionerEdgeOptions& precon, bool known_connected,
                            GncCentralizedResult& out) {
  const PoseGraph& g = in.graph;
  PreconditionerEdgeOptions budget = precon;
  if (!known_connected) budget.max_flops = 0;
  const PreconditionerEdges edges =
      select_preconditioner_edges(g.d, g.num_poses, g.measurements, in.weights, in.known, budget);
  CentralizedResult solve =
      edges.all ? solve_centralized(g, solver) : solve_centralized(g, solver, &edges.kept);
  GncSolveWork work;
  work.trust_region_iterations = solve.iterations;
  for (const CentralizedIteration& step : solve.trace)
    work.cg_iterations += step.tr.inner_iterations;
  work.measurements = g.num_measurements();
  work.preconditioner_measurements = edges.kept.size();
  work.full_flops = edges.full_flops;
  work.preconditioner_flops = edges.kept_flops;
  out.inner_iterations += work.trust_region_iterations;
  out.cg_iterations += work.cg_iterations;
  out.solves.push_back(work);
  return solve;
}

}  // namespace

void GncCentralizedOptions::validate() const {
  solver.validate();
  robust.validate();
  preconditioner.validate();
  if (cluster_probes < 0)
    throw InputError("GncCentralizedOptions.cluster_probes = " + std::to_string(cluster_probes) +
                     ": must be >= 0 (0 = none)");
  clusters.validate();
}

GncCentralizedResult solve_gnc_centralized(const PoseGraph& graph,
                                           const GncCentralizedOptions& options) {
  options.validate();
  if (!options.known_inlier_flags.empty() &&
      options.known_inlier_flags.size() != graph.num_measurements())
    throw std::invalid_argument("solve_gnc_centralized: one known-inlier flag per measurement");
  GncCentralizedResult out;
  const RobustOptions& robust = options.robust;
  const std::size_t m = graph.num_measurements();
  std::vector<bool> known(m);
  for (std::size_t e = 0; e < m; ++e)
    known[e] = is_known_inlier(graph.measurements[e], robust.known_inliers) ||
               (!options.known_inlier_flags.empty() && options.known_inlier_flags[e]);
  out.threshold_squared = tls_threshold_squared(
      robust, graph.d, static_cast<std::size_t>(std::count(known.begin(), known.end(), false)));
  const double c2 = out.threshold_squared;
  // A measurement of weight exactly 0 adds nothing to the weighted cost; when the known inliers
  // keep the poses connected it leaves the weighted solve (as in the distributed engine) instead
  // of staying at kMinInnerWeight: wrong closures between random poses are what fills the
  // factor of the weighted problem.
  const PoseGraph known_graph = known_subgraph(graph, known);
  const bool known_connected = count_components(known_graph) <= 1;
  auto weighted_solve_input = [&](const std::vector<double>& weights,
                                  const std::vector<Pose>& start) {
    SolveInput in{weighted_graph(graph, weights, start), weights, known};
    if (!known_connected) return in;
    std::vector<std::size_t> zero;
    in.weights.clear();
    in.known.clear();
    for (std::size_t e = 0; e < weights.size(); ++e) {
      if (weights[e] == 0) {
        zero.push_back(e);
      } else {
        in.weights.push_back(weights[e]);
        in.known.push_back(known[e]);
      }
    }
    if (!zero.empty()) in.graph = inlier_graph(in.graph, zero, start);
    return in;
  };
  auto run = [&](SolveInput in, const CentralizedOptions& solver) {
    return run_solve(in, solver, options.preconditioner, known_connected, out);
  };

  // pcm-gnc: closures outside the largest pairwise-consistent set start with weight 0.
  std::vector<bool> dropped(m, false);
  if (robust.kind == RobustKind::kPcmGnc) {
    if (!known_connected)
      throw InputError(graph.source, 0,
                       "robust pcm-gnc: the known inliers do not connect the poses, so there is "
                       "no odometry to test closures against (use --robust gnc-tls)");
    out.pcm = pairwise_consistency(graph, known, distributed_initialization(known_graph, 1), c2);
    for (std::size_t e : out.pcm.inconsistent) dropped[e] = true;
  }

  // Inner solves: no certificate (it only matters for the final inlier set), warm start, and
  // with RobustOptions::inner_max_iterations at most that many trust-region steps (off by
  // default: where the start is far from the optimum, GNC needs real minimisers).
  CentralizedOptions inner = options.solver;
  inner.certify = false;
  // One thread: the weighted solves start from given poses, so there is no start to factor
  // beside (the first solve only loses that overlap), and on one thread a dense factor (wrong
  // closures between random poses) is computed supernodally (CentralizedOptions::
  // supernodal_min_flops).
  inner.threads = 1;
  // The Euclidean factor of the weighted Q: with wrong closures between random poses the tangent
  // factor (6 coordinates a 3D pose against 4 rows) is dense and refactored for every weighted
  // solve (a generated 1000-pose 3D grid with 25 % random outliers: 1.6 -> 4.1 s CPU).
  inner.preconditioning = CentralizedPreconditioning::kEuclidean;
  if (robust.inner_max_iterations > 0)
    inner.trust_region.max_iterations =
        std::min(inner.trust_region.max_iterations, robust.inner_max_iterations);
  std::vector<double> first(m, 1.0);  // plain least squares (pcm-gnc: without the dropped)
  for (std::size_t e = 0; e < m; ++e)
    if (dropped[e]) first[e] = 0.0;
  CentralizedResult solve;
  if (robust.kind == RobustKind::kPcmGnc) {
    solve = run(weighted_solve_input(first, graph.initial), inner);
  } else if (options.known_inlier_start && known_connected &&
             options.solver.initialization == Initialization::kChordal) {
    PoseGraph start_graph = graph;
    start_graph.initial = chordal_initialization(graph);
    std::vector<Pose> known_start = chordal_initialization(known_graph);
    if (tls_cost(graph, known, known_start, c2) < tls_cost(graph, known, start_graph.initial, c2)) {
      start_graph.initial = std::move(known_start);
      out.started_from_known_inliers = true;
    }
    CentralizedOptions from_start = inner;
    from_start.initialization = Initialization::kFile;
    solve = run({std::move(start_graph), first, known}, from_start);
  } else {
    solve = run({graph, first, known}, inner);
  }
  inner.initialization = Initialization::kFile;

  out.weights.assign(m, 1.0);
  std::vector<double> r2 = residuals(graph, solve.poses);
  double max_r2 = 0;
  for (std::size_t e = 0; e < m; ++e) {
    if (dropped[e]) out.weights[e] = 0.0;
    if (!known[e] && !dropped[e]) max_r2 = std::max(max_r2, r2[e]);
  }
  double mu = gnc_initial_mu(max_r2, c2);
  out.weights_converged = mu == 0;  // every residual inside the bound: nothing to reject
  while (!out.weights_converged && out.outer_iterations < robust.max_outer_iterations) {
    double spread = 0;
    for (std::size_t e = 0; e < m; ++e) {
      out.weights[e] = known[e] ? 1.0 : dropped[e] ? 0.0 : tls_weight(r2[e], c2, mu);
      spread += out.weights[e] * (1 - out.weights[e]);
    }
    solve = run(weighted_solve_input(out.weights, solve.poses), inner);
    ++out.outer_iterations;
    out.final_mu = mu;
    r2 = residuals(graph, solve.poses);
    out.weights_converged = spread <= robust.weight_tolerance;
    mu *= robust.mu_step;
  }

  for (std::size_t e = 0; e < m; ++e)
    if (out.weights[e] < 0.5) out.rejected.push_back(e);
  // Re-check passes (RobustOptions::readmission_passes): at the inlier set's solution every
  // measurement that may be rejected is judged by TLS itself: a rejected one within the bound
  // (r^2 <= c^2) comes back, a kept one beyond it leaves, and the new set is solved again. Each
  // pass is a step of block-coordinate descent on the TLS cost (binary weights given the poses,
  // then the poses given the weights), so the TLS cost never rises. Kept measurements beyond the
  // bound are wrong closures that GNC's last iterate still fitted with the help of a distortion;
  // without them the solve relaxes it.
  CentralizedOptions final_options = options.solver;
  final_options.initialization = Initialization::kFile;
  final_options.threads = 1;
  // The re-check passes from `rejected` and `start`, solved with `solver`.
  struct KeptSet {
    CentralizedResult solve;
    std::vector<std::size_t> rejected;
    std::size_t readmitted = 0, late_rejected = 0;
  };
  auto solve_kept_set = [&](std::vector<std::size_t> rejected, std::vector<Pose> start,
                            const CentralizedOptions& solver) {
    KeptSet kept;
    kept.rejected = std::move(rejected);
    for (int pass = 0;; ++pass) {
      PoseGraph inliers = inlier_graph(graph, kept.rejected, start);
      require_connected_inliers(graph, inliers, kept.rejected.size());
      // Start from the cheaper of the last estimate and the chordal guess of the kept set: an
      // estimate that GNC bent around wrong closures can lead the local solve to a poor solution
      // of the kept set, and without the wrong closures chordal is close to its optimum again
      // (the distributed passes vote the same way).
      const std::vector<Pose> guess = chordal_initialization(inliers);
      if (evaluate_objective(inliers, guess) < evaluate_objective(inliers, start))
        inliers.initial = guess;
      std::vector<bool> kept_known;
      kept_known.reserve(inliers.num_measurements());
      for (std::size_t e = 0, next = 0; e < m; ++e) {
        if (next < kept.rejected.size() && kept.rejected[next] == e)
          ++next;
        else
          kept_known.push_back(known[e]);
      }
      const std::vector<double> ones(inliers.num_measurements(), 1.0);
      kept.solve = run({std::move(inliers), ones, std::move(kept_known)}, solver);
      if (pass == robust.readmission_passes || kept.rejected.empty()) break;
      const std::vector<Pose>& poses = kept.solve.poses;
      TlsRecheck verdict = tls_recheck(graph, known, poses, c2, kept.rejected);
      if (verdict.rejected == kept.rejected) break;
      kept.readmitted += verdict.taken_back;
      kept.late_rejected += verdict.dropped;
      kept.rejected = std::move(verdict.rejected);
      start = poses;
    }
    return kept;
  };
  auto adopt = [&](KeptSet&& kept) {
    out.final_solve = std::move(kept.solve);
    out.readmitted += kept.readmitted;
    out.late_rejected += kept.late_rejected;
    out.rejected = std::move(kept.rejected);
  };
  adopt(solve_kept_set(out.rejected, solve.poses, final_options));

  // Probes (GncCentralizedOptions::cluster_probes, RobustOptions::recheck_probes,
  // probe_return_ratio): a few wrong closures can bend the map until each fits within the bound,
  // so a tail probe cuts the kept closures far above the median residual together; a run of
  // wrong closures that fit each other survives every one-at-a-time verdict, so a cluster probe
  // cuts a whole run of kept closures at once; a true closure just beyond the bound at the kept
  // set's solution stays out until it is back in the problem, so a return probe brings it back.
  // The re-check passes then run from there, and the result stays only when the TLS cost over
  // every measurement falls: each kept probe is a descent step of the TLS cost, a refused one
  // changes nothing. Without cluster probes one return probe may run (--gnc-probes 0: no probe).
  const bool may_probe =
      robust.recheck_probes > 0 && robust.readmission_passes > 0 && known_connected;
  ProbeRules rules;
  rules.budget = options.cluster_probes > 0 ? options.cluster_probes : may_probe ? 1 : 0;
  rules.cut_clusters = options.cluster_probes > 0;
  rules.clusters = options.clusters;
  rules.return_ratio = may_probe ? robust.probe_return_ratio : 1.0;
  rules.tail_probes = may_probe ? robust.recheck_probes : 0;
  rules.tail_cut_ratio = robust.probe_ratio;
  rules.tail_ratio = robust.probe_tail_ratio;
  if ((rules.budget > 0 || rules.tail_probes > 0) && !out.rejected.empty()) {
    CentralizedOptions trial = final_options;
    trial.certify = false;  // only the set that stays is certified
    KeptSet last;
    const ClusterProbeCounts counts = search_cluster_probes(
        graph, known, c2, rules, out.rejected, out.final_solve.poses,
        [&](std::vector<std::size_t> rejected) {
          last = solve_kept_set(std::move(rejected), out.final_solve.poses, trial);
          return ClusterProbeTrial{last.rejected, last.solve.poses};
        },
        [&] { adopt(std::move(last)); });
    out.probes = counts.probes;
    out.probes_kept = counts.kept;
    out.readmitted += counts.returned;
  }
  // Swap probes (RobustOptions::swap_probes): a kept closure and a rejected one beside it trade
  // places, kept only when the TLS cost falls (swap_probe.hpp).
  SwapRules swaps;
  swaps.budget = robust.readmission_passes > 0 && known_connected ? robust.swap_probes : 0;
  swaps.near = robust.swap_near;
  swaps.kept_ratio = robust.swap_kept_ratio;
  swaps.return_ratio = robust.swap_return_ratio;
  swaps.alone_ratio = robust.probe_ratio;
  if (swaps.budget > 0 && !out.rejected.empty()) {
    CentralizedOptions trial = final_options;
    trial.certify = false;
    KeptSet last;
    const SwapProbeCounts counts = search_swap_probes(
        graph, known, c2, swaps, out.rejected, out.final_solve.poses,
        [&](std::vector<std::size_t> rejected) {
          last = solve_kept_set(std::move(rejected), out.final_solve.poses, trial);
          return ClusterProbeTrial{last.rejected, last.solve.poses};
        },
        [&] { adopt(std::move(last)); });
    out.swap_probes = counts.probes;
    out.swap_probes_kept = counts.kept;
  }
  // The certificate (and the staircase) for the set that stayed.
  if (out.probes_kept + out.swap_probes_kept > 0)
    adopt(solve_kept_set(out.rejected, out.final_solve.poses, final_options));
  if (out.readmitted + out.late_rejected > 0 || out.probes_kept + out.swap_probes_kept > 0)
    for (std::size_t e = 0; e < m; ++e)
      if (!known[e])
        out.weights[e] =
            std::binary_search(out.rejected.begin(), out.rejected.end(), e) ? 0.0 : 1.0;
  return out;
}

}  // namespace tessera
