#pragma once
// The centralized trust region's preconditioner: the tangent-coordinate factor
// (<tessera/solvers/tangent_preconditioner.hpp>) at rank-d points, the Euclidean factor of
// Q + lambda I (<tessera/solvers/block_preconditioner.hpp>) above rank d (after a saddle escape).
//
// Why the tangent factor: the Euclidean one followed by the tangent projection is far from the
// inverse Hessian where Q is nearly singular along the lifted gauge (parking-garage: 697 tCG
// iterations to the reference's stop, 28 with the tangent factor), and its predicted decrease
// 1/2 <P g, g> overstates the remaining gap 0.3-50x; the tangent factor is the exact inverse of
// the Hessian's Q part on the tangent space, so the prediction is close to the true gap.
//
// Why refactor by a budget: A depends on the rotations, so a factor from an earlier point is
// less exact (more tCG iterations) but still a valid preconditioner. At a new iterate the factor
// is recomputed once the solves done with it since its factorization cost as much as one
// factorization (CHOLMOD's predicted flops against 4 x factor entries a solve): graphs whose tCG
// needs few iterations (torus3D, a 3D factor 3-4x the flops of the Euclidean one) keep the first
// factor, long chains (ais2klinik, cheap 2D factors, many iterations) refactor most steps.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/riemannian_preconditioner.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>

namespace tessera {

class CentralizedPreconditioner : public RiemannianPreconditioner {
 public:
  using EuclideanBuilder = std::function<std::unique_ptr<BlockPreconditioner>()>;

  /// `tangent`: factored at the start (may be null or unusable: then the Euclidean factor is
  /// used everywhere). `euclidean`: builds the Euclidean factor on first use (above rank d, or
  /// when the tangent factor is unusable). `refresh_ratio` (>= 0): refactor at a new rank-d
  /// point once the solves since the last factorization cost refresh_ratio x a factorization;
  /// 0 = never refactor.
  CentralizedPreconditioner(std::unique_ptr<TangentPreconditioner> tangent,
                            EuclideanBuilder euclidean, double refresh_ratio);
  ~CentralizedPreconditioner() override;

  /// The tangent factor at rank-d points, else the Euclidean one. Not thread-safe: the trust
  /// region calls it from one thread (it refactors and builds lazily).
  Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                        const Eigen::MatrixXd& V) const override;

  /// The Euclidean factor (built now if it was not yet).
  const BlockPreconditioner& euclidean() const;
  /// Numeric factorizations of the tangent factor so far (the first one included).
  int tangent_factorizations() const;
  /// True once the Euclidean factor was built.
  bool euclidean_built() const;

 private:
  bool tangent_usable() const;

  std::unique_ptr<TangentPreconditioner> tangent_;
  EuclideanBuilder build_euclidean_;
  double refresh_ratio_;
  mutable std::unique_ptr<BlockPreconditioner> euclidean_;
  // The last rank-d point seen, and the solves done since the last factorization.
  mutable Eigen::MatrixXd point_;
  mutable double solves_since_factor_ = 0;
};

}  // namespace tessera
