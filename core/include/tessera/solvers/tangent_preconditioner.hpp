#pragma once
// Tangent-coordinate preconditioner for a block's trust-region steps at rank r = d (the agents'
// active rows after a chordal or distributed lift; docs/irbcd.md section 5).
//
// Why: the Euclidean preconditioner (2 (Q_BB + lambda I))^{-1} followed by the tangent projection
// (block_preconditioner.hpp) is far from the inverse of the Hessian on the tangent space when a
// block is held by few cut edges: Q_BB is then nearly singular along the lifted gauge X -> M X,
// whose normal components Q_BB^{-1} amplifies and the projection throws away (parking-garage: ~44
// tCG iterations per update, docs/irbcd.md section 5). Working in tangent coordinates avoids it.
//
// What: each pose i = [Y_i | t_i] (Y_i in O(d)) gets p = d(d+1)/2 coordinates c_i = (omega, u):
// rotation part Y_i Omega(omega) (Omega: the skew basis E_ab = e_b e_a^T - e_a e_b^T, a < b) and
// translation Y_i u, both in the pose's own frame, so that A below depends on the rotations only
// through the relative rotations Y_i^T Y_j. These columns form a basis J(X) of the tangent space.
// With A = J^T (2 Q_BB) J + lambda I (the tangent restriction of the block's Euclidean Hessian,
// pdm x pdm, the pattern of Q_BB in p x p pose blocks) the preconditioner is
//     P(X) V = J(X) A^{-1} J(X)^T V,
// which is exactly (Proj_X 2 Q_BB restricted to the tangent space)^{-1} when A was computed at X
// (and lambda = 0), and is a symmetric positive definite map of the tangent space at X onto
// itself for any X whose rotations are orthogonal, also when A is from an earlier point (A is
// then "stale": still a valid preconditioner, merely less exact).
//
// A's pattern is analysed once (CHOLMOD, AMD); factorize() recomputes the values at a new point
// and refactors numerically with the same symbolic factor.

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <tessera/problem/block_problem.hpp>
#include <tessera/solvers/riemannian_preconditioner.hpp>

namespace tessera {

class TangentPreconditioner : public RiemannianPreconditioner {
 public:
  /// `relative_shift`: lambda = relative_shift * max diagonal entry of J^T 2 Q_BB J (>= 0; keeps
  /// A positive definite for a block whose tangent Hessian is singular, e.g. one without cut
  /// edges). `max_factor_entries`: when CHOLMOD's symbolic analysis predicts a larger factor,
  /// usable() is false (the caller keeps its Euclidean preconditioner); 0 = no limit.
  /// `supernodal_min_flops`: when CHOLMOD's analysis predicts a factorization of more
  /// floating-point operations, the factor is supernodal LL^T (dense BLAS kernels on its
  /// supernodes) instead of simplicial LDL^T; 0 = always simplicial (same operator up to
  /// round-off). `simplicial_solves`: such a factor is converted to the simplicial LDL^T form
  /// after each factorization, so that its solves (a few right-hand sides each) avoid the
  /// supernodal solve's BLAS calls on small supernodes, and grow() still applies; the factor
  /// keeps the simplicial factor's fill-reducing ordering. Only the factorization's kernels
  /// change (same operator up to round-off).
  explicit TangentPreconditioner(const BlockProblem& problem, double relative_shift = 1e-9,
                                 std::size_t max_factor_entries = 16'000'000,
                                 double supernodal_min_flops = 0, bool simplicial_solves = false);
  ~TangentPreconditioner() override;
  TangentPreconditioner(const TangentPreconditioner&) = delete;
  TangentPreconditioner& operator=(const TangentPreconditioner&) = delete;

  /// False when the factor would be too large or a factorization failed: never usable then.
  bool usable() const;
  /// True when a factor is held (factorize() succeeded at least once and usable()).
  bool factored() const;

  /// Computes A at X (d x (d+1)m, each rotation block orthogonal) and factors it. Returns false
  /// when X does not have d rows, or when the factorization fails (then usable() becomes false).
  bool factorize(const Eigen::MatrixXd& X);
  /// The same with the Hessian's second-order part: A = J^T 2 (Q_BB - Lambda(X)) J + lambda I,
  /// Lambda_i = sym(Y_i^T egrad_i) / 2 the first-order multipliers of pose i (`egrad` = 2 X Q_BB,
  /// the block's Euclidean gradient at X), i.e. the Riemannian Hessian in tangent coordinates.
  /// Where that A is not positive definite (far from a minimiser) A is factored without Lambda.
  /// Returns what factorize(X) returns; with_multipliers() says which A was factored.
  bool factorize(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad);
  /// True when the last factorization included the multipliers.
  bool with_multipliers() const;

  /// Readies the factor for an update at X: factors A at X on the first call and, when
  /// `refresh_interval` > 0, again on every refresh_interval-th call after it (0: built once).
  /// Returns true when apply() may be used at X (X has d rows and a factor is held).
  bool prepare(const Eigen::MatrixXd& X, int refresh_interval);

  /// The block grew (`problem` after BlockProblem::extend, `X` its rank-d point with the new
  /// poses appended): the poses after the factored ones (this growth's and earlier ones') are
  /// appended to the held factor with their couplings to the factored poses kept, through the
  /// grown poses' Schur complement (the new measurements' share of A on the old poses they
  /// touch enters by a low-rank correction). The old poses' own block stays the held factor's,
  /// from the point it was factored at: still symmetric positive definite, merely less exact,
  /// so a growing block is not refactored for every few poses. Returns false
  /// (nothing changed) when no factor is held, X does not fit or the grown part is not positive
  /// definite. factorize() then refuses (the caller builds a new preconditioner for the grown
  /// block).
  bool grow(const BlockProblem& problem, const Eigen::MatrixXd& X);
  /// Poses appended to the factor by grow().
  Eigen::Index grown_poses() const;

  /// J(X) A^{-1} J(X)^T V for a tangent vector V at X (d rows): a tangent vector at X.
  Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                        const Eigen::MatrixXd& V) const override;

  /// Numeric factorizations done so far.
  int factorizations() const;
  /// Entries of the Cholesky factor predicted by the symbolic analysis.
  std::size_t factor_entries() const;
  /// Floating-point operations of one factorization, as the symbolic analysis predicts them
  /// (0 when no analysis was done).
  double factor_flops() const;
  /// True when the factor is supernodal (see supernodal_min_flops).
  bool supernodal() const;
  /// True when the factorizations are supernodal and the factor is converted to the simplicial
  /// form for the solves (supernodal_min_flops with simplicial_solves).
  bool supernodal_factorization() const;
  /// Coordinates per pose, d(d+1)/2.
  int coordinates_per_pose() const;
  /// The simplicial solves' backward dots as four partial sums (LdlChainSolve::set_split_dots):
  /// fewer cycles, but no longer CHOLMOD's bits (the same operator up to round-off). Off by
  /// default; kept across factorizations.
  void set_split_dots(bool split);

  /// The basis J(X) of the tangent space at X, one column per coordinate (pose after pose,
  /// rotation then translation coordinates): for tests and diagnostics.
  Eigen::MatrixXd basis(const Eigen::MatrixXd& X) const;

 private:
  bool factorize_impl(const Eigen::MatrixXd& X, const Eigen::MatrixXd* egrad);

  struct Factor;
  std::unique_ptr<Factor> factor_;
};

}  // namespace tessera
