#pragma once
// Preconditioner for trust-region steps on a BlockProblem: the Euclidean Hessian 2 Q_BB is
// approximated by 2 (Q_BB + lambda I), factored once with CHOLMOD; applying it solves with
// the factor and projects back onto the tangent space. lambda keeps the factorization
// defined for blocks whose Q_BB is singular (the global translation gauge).
// When the exact factor would be too large (3D grids with tens of thousands of poses per block:
// fill grows like m^(4/3), and a 20,000-pose block's factor takes ~100 MB, ~9 s to compute and
// ~0.25 s per solve), the preconditioner falls back to the block diagonal of Q_BB + lambda I
// (one (d+1) x (d+1) block per pose): memory and time linear in m, more tCG iterations.
// (Basing it on the certificate matrix S(X) = Q - Lambda(X), the Hessian's exact Euclidean
// part near a critical point, was tried: no fewer tCG iterations on kitti_02 (1598 vs 1588)
// for one extra factorization per step, so the fixed Q-based factor stays.)

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <tessera/problem/block_problem.hpp>
#include <tessera/solvers/riemannian_preconditioner.hpp>

namespace tessera {

class BlockPreconditioner : public RiemannianPreconditioner {
 public:
  /// Factor entries above which the distributed agents use the block-diagonal fallback
  /// (16 M entries = 128 MB of factor; no benchmark graph's block comes near it).
  static constexpr std::size_t kDefaultMaxFactorEntries = 16'000'000;

  /// Factor entries above which the exact factor is supernodal LL^T rather than simplicial
  /// LDL^T (1 M entries = 8 MB; measured crossover ~0.6 M, see the .cpp).
  static constexpr std::size_t kDefaultSupernodalMinEntries = 1'000'000;
  /// lambda relative to the largest diagonal entry of Q_BB.
  static constexpr double kDefaultRelativeShift = 1e-6;

  /// `relative_shift`: lambda = relative_shift * max diagonal entry of Q_BB.
  /// `max_factor_entries`: when CHOLMOD's symbolic analysis predicts a larger Cholesky factor,
  /// use the block-diagonal fallback instead; 0 = always the exact factor.
  /// `supernodal_min_entries`: exact factors with more entries are supernodal (same operator
  /// up to round-off); 0 = always simplicial.
  /// `supernodal_min_flops`: exact factors whose factorization CHOLMOD's analysis predicts to
  /// take more floating-point operations are supernodal too; 0 = no such rule.
  /// `simplicial_solves`: a supernodal factor, once computed, is converted to the simplicial
  /// LDL^T form for the solves (the same factor; faster to solve with a few right-hand sides).
  explicit BlockPreconditioner(const BlockProblem& problem,
                               double relative_shift = kDefaultRelativeShift,
                               std::size_t max_factor_entries = kDefaultMaxFactorEntries,
                               std::size_t supernodal_min_entries = kDefaultSupernodalMinEntries,
                               double supernodal_min_flops = 0, bool simplicial_solves = false);
  ~BlockPreconditioner() override;
  BlockPreconditioner(const BlockPreconditioner&) = delete;

  /// Whether BlockPreconditioner(problem, relative_shift, max_factor_entries, ...) would take the
  /// block-diagonal fallback (block_diagonal()), decided as the constructor decides it (the
  /// lower triangle's size, then CHOLMOD's symbolic analysis) without any numeric
  /// factorization: for a caller that needs the decision but not the factor (an agent whose
  /// tangent factor replaces this one; cubicle, 5 agents: 787 M instructions of numeric
  /// factorization saved, against 83 M for the analysis).
  static bool falls_back(const BlockProblem& problem, double relative_shift,
                         std::size_t max_factor_entries);
  BlockPreconditioner& operator=(const BlockPreconditioner&) = delete;

  /// Tangent projection at X of (2(Q_BB + lambda I))^{-1} applied to the rows of V.
  Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                        const Eigen::MatrixXd& V) const override;

  /// True when the exact factor was too large and the block diagonal is used.
  bool block_diagonal() const;
  /// True when the exact factor was computed supernodally (solves may use it converted to
  /// simplicial form, see simplicial_solves).
  bool supernodal() const;
  /// Entries of the exact factor as its symbolic analysis predicted them (0 for the block
  /// diagonal fallback).
  std::size_t factor_entries() const;
  /// Floating-point operations of the exact factorization, CHOLMOD's prediction (0 for the
  /// block diagonal fallback).
  double factor_flops() const;

 private:
  struct Factor;
  std::unique_ptr<Factor> factor_;
};

}  // namespace tessera
