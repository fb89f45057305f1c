#pragma once
// GNC-TLS around the centralized certifiable solver (`tessera solve --algorithm centralized
// --robust gnc-tls`): a plain solve, then outer steps of (closed-form weight update,
// warm-started weighted solve) while mu grows, then the certified solve of the inlier set.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <tessera/robust/pairwise_consistency.hpp>
#include <tessera/robust/robust_options.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/solvers/preconditioner_edges.hpp>
#include <vector>

namespace tessera {

struct GncCentralizedOptions {
  /// Settings of every solve. The inner (weighted) solves run without the certificate and
  /// start from the previous solve's poses; the final solve of the inlier set uses them as
  /// given (certify on: `certified` is then about the inlier set).
  CentralizedOptions solver;
  RobustOptions robust;  ///< kPcmGnc: the consistency check first; otherwise GNC-TLS.
  /// Empty, or one flag per measurement: true = never down-weighted, like the known-inlier
  /// rule's measurements (a dpgo CSV file's is_known_inlier column).
  std::vector<bool> known_inlier_flags;
  /// With solver.initialization kChordal and GNC-TLS: the first solve starts from the cheaper,
  /// in TLS cost (known inliers r^2, the others min(r^2, c^2)), of the chordal guess and the
  /// known inliers' own chordal initialization (the odometry chain when they are the odometry),
  /// as the distributed engine's start vote does. The chordal guess fits every measurement,
  /// wrong ones too, and then settles in a distorted solution; on clean data it is nearly the
  /// optimum, where the odometry chain's drift can lead the plain solve to another critical
  /// point whose residuals GNC then cuts. Unused when the known inliers do not connect the poses.
  bool known_inlier_start = true;
  /// Which measurements each solve's preconditioner factors (solvers/preconditioner_edges.hpp):
  /// the known inliers always, the others by current weight while the predicted factorization
  /// flops stay within preconditioner.max_flops. Wrong closures between random poses fill the
  /// whole graph's factor (city10000 at 25 % random outliers: 7.9e10 flops) while their weights
  /// fall towards 0; the solves' iterates differ from the full preconditioner's only through the
  /// truncated CG. A graph whose full factor fits the budget (every clean shared graph) is solved
  /// exactly as with the full preconditioner. max_flops = 0: always the full one.
  PreconditionerEdgeOptions preconditioner;
  /// Most cluster probes after the re-check passes, >= 0 (0 = none). A probe cuts one cluster of
  /// kept closures that run side by side (closure_clusters.hpp, the one with the most rejected
  /// closures near it that was not tried yet), runs the re-check passes from there and keeps the
  /// result only when the TLS cost over every measurement falls. Why: a run of wrong closures
  /// between two look-alike stretches bends the map until all of them fit, and the true closures
  /// of the stretch are cut instead; no one-at-a-time verdict undoes that, while the truth has
  /// the lower TLS cost (intel with group outliers; docs/benchmarks/robust.md, "Group outliers").
  /// When no cluster is left, the budget's return probes (RobustOptions::probe_return_ratio)
  /// follow: the rejected closures just beyond the bound come back together, then one at a time.
  /// Without cluster probes one return probe runs (RobustOptions::recheck_probes > 0).
  /// Besides these, up to RobustOptions::recheck_probes tail probes run first, with the
  /// distributed probe's rule (probe_ratio, probe_tail_ratio) over all kept measurements: when
  /// their mean r^2 is above probe_tail_ratio x their median, the kept ones above probe_ratio x
  /// the median leave together and the return band comes back; kept only if the TLS cost falls
  /// (manhattan3500 with 50 % random outliers: 2 wrong closures kept at r^2 20 and 5.4 against a
  /// median of 0.04 and 4 true ones cut without it, exactly the 977 wrong ones with it).
  int cluster_probes = 0;
  ClosureClusterOptions clusters;  ///< Which kept closures form a cluster.
  /// Throws InputError naming the first bad field.
  void validate() const;
};

/// The work of one solve of the robust loop: its truncated CG against its preconditioner.
struct GncSolveWork {
  int trust_region_iterations = 0;
  int cg_iterations = 0;
  std::size_t measurements = 0;                 ///< Measurements of the solved problem.
  std::size_t preconditioner_measurements = 0;  ///< Of those, the preconditioner's.
  double full_flops = 0;                        ///< Predicted factorization flops with all of them.
  double preconditioner_flops = 0;  ///< Predicted factorization flops of the preconditioner.
};

struct GncCentralizedResult {
  /// The final solve on the inlier graph: poses, cost over the kept measurements, certificate.
  CentralizedResult final_solve;
  std::vector<double> weights;        ///< Last weight of every measurement, in [0, 1].
  std::vector<std::size_t> rejected;  ///< Measurements with weight 0 (< 0.5 if never binary).
  int outer_iterations = 0;           ///< Weighted solves after the first plain one.
  int inner_iterations = 0;           ///< Trust-region iterations of every solve, final included.
  int cg_iterations = 0;              ///< Their truncated-CG iterations (the work of a solve).
  double threshold_squared = 0;       ///< c^2 used.
  double final_mu = 0;                ///< mu of the last outer step (0: no step was needed).
  bool weights_converged = false;     ///< sum w(1 - w) fell below the tolerance.
  /// Rejected measurements taken back by the re-check passes (RobustOptions::readmission_passes)
  /// and by kept return probes.
  std::size_t readmitted = 0;
  /// Kept measurements beyond the bound at an inlier set's solution, rejected by a re-check pass.
  std::size_t late_rejected = 0;
  PairwiseConsistencyResult pcm;  ///< kPcmGnc: the consistency check (empty otherwise).
  /// Probes run: cluster probes (GncCentralizedOptions::cluster_probes) and return probes
  /// (RobustOptions::probe_return_ratio), within the budget (at most one without cluster probes).
  int probes = 0;
  int probes_kept = 0;  ///< Of those, the ones that lowered the TLS cost and stayed.
  /// Swap probes run after those (RobustOptions::swap_probes) and the ones that stayed.
  int swap_probes = 0;
  int swap_probes_kept = 0;
  /// The start vote (GncCentralizedOptions::known_inlier_start) chose the known inliers' start.
  bool started_from_known_inliers = false;
  /// Every solve in order: the first (plain) one, the weighted ones, the kept set's.
  std::vector<GncSolveWork> solves;
};

/// Runs GNC-TLS on `graph` and certifies the result on the inlier set. Measurements that the
/// known-inlier rule names keep weight 1. Throws InputError on invalid options, and when the
/// kept measurements no longer connect the poses (e.g. every measurement looks like an
/// outlier): the message says how many were rejected and how many parts remain, instead of
/// returning a collapsed estimate.
GncCentralizedResult solve_gnc_centralized(const PoseGraph& graph,
                                           const GncCentralizedOptions& options);

}  // namespace tessera
