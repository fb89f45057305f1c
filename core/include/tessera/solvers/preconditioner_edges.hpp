#pragma once
// Which measurements a trust-region preconditioner factors. A preconditioner need not hold every
// edge of the problem: any connected subset gives a positive definite approximation of the
// Hessian, and the truncated CG pays for the missing edges with more iterations. Wrong loop
// closures between random poses make the whole graph's factor dense (CHOLMOD's predicted flops:
// city10000 with 25 % random outliers 7.9e10, torus3D at 50 % 4.4e10, against <= 3.6e8 on every
// clean shared graph), while most of them carry a small weight in a robust solve's weighted
// problem. The selection keeps the measurements that must stay (the known inliers: odometry
// connects the poses) and then as many of the others as the flop budget allows, highest weight
// first and, among equal weights, the shortest in pose-id distance first (edges close in the
// odometry order add little fill).

#include <cstddef>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera {

struct PreconditionerEdgeOptions {
  /// Most floating-point operations the preconditioner's factorization may take, as predicted by
  /// CHOLMOD's symbolic analysis (AMD) of the pose adjacency, times (d+1)^3 for the blocks of the
  /// data matrix; >= 0, 0 = no limit (always every measurement). While every measurement fits,
  /// the preconditioner is exactly the full one. 1e9: about 3x the densest clean shared graph
  /// (torus3D, 3.6e8), a fraction of a second to factor.
  double max_flops = 1e9;
  /// Throws InputError naming the bad field.
  void validate() const;
};

struct PreconditionerEdges {
  /// Indices (ascending) of the measurements the preconditioner factors.
  std::vector<std::size_t> kept;
  bool all = true;        ///< kept holds every measurement.
  double full_flops = 0;  ///< Predicted factorization flops with every measurement.
  double kept_flops = 0;  ///< Predicted factorization flops with the kept ones.
  int analyses = 0;       ///< Symbolic analyses the selection ran (its own cost).
};

/// Predicted floating-point operations of the Cholesky factorization of the data matrix of
/// `measurements` on `num_poses` poses in dimension d (AMD ordering of the pose adjacency; each
/// scalar entry stands for a (d+1) x (d+1) block).
double predicted_factor_flops(int d, std::size_t num_poses,
                              const std::vector<Measurement>& measurements);

/// Chooses the preconditioner's measurements. `weights`: one per measurement (the robust solve's
/// current weights; all 1 for a plain solve), ranks the optional ones. `required`: empty or one
/// flag per measurement; flagged ones are always kept, whatever the budget (they should connect
/// the poses, or the factor is held together only by the diagonal shift). Throws InputError on
/// invalid options, std::invalid_argument on mismatched sizes.
PreconditionerEdges select_preconditioner_edges(int d, std::size_t num_poses,
                                                const std::vector<Measurement>& measurements,
                                                const std::vector<double>& weights,
                                                const std::vector<bool>& required,
                                                const PreconditionerEdgeOptions& options);

}  // namespace tessera
