#pragma once
// The centralized trust region's preconditioner: the tangent-coordinate factor
// (<tessera/solvers/tangent_preconditioner.hpp>) or the Euclidean factor of Q + lambda I
// (<tessera/solvers/block_preconditioner.hpp>) at rank-d points, the Euclidean one above rank d
// (after a saddle escape).
//
// Why the tangent factor: the Euclidean one followed by the tangent projection is far from the
// inverse Hessian where Q is nearly singular along the lifted gauge (parking-garage: 984 tCG
// iterations to the reference's stop, 34 with the tangent factor), and its predicted decrease
// 1/2 <P g, g> overstates the remaining gap 0.3-50x; the tangent factor is the exact inverse of
// the Hessian's Q part on the tangent space, so the prediction is close to the true gap.
//
// Why start with the Euclidean factor on some graphs: where it already needs few tCG iterations
// (torus3D: 20 to the stop, 13 with the tangent factor) the 3D tangent factor (6 coordinates a
// pose against 4 rows, 3.4x the flops on torus3D) costs more than it saves. Started so, the
// factor switches to the tangent one as soon as one step's solves with the Euclidean factor have
// cost a set fraction of a tangent factorization: a step that needs many iterations predicts the
// same for the steps to come. The switch happens at the point of that step's tCG (which is ended
// there: changes_at_next_apply()), so a graph that needs the tangent factor loses that fraction
// of a factorization, not a whole step.
//
// Why refactor by a budget: A depends on the rotations, so a factor from an earlier point is
// less exact (more tCG iterations) but still a valid preconditioner. At a new iterate the factor
// is recomputed once the solves done with it since its factorization cost as much as one
// factorization (CHOLMOD's predicted flops against 4 x factor entries a solve): graphs whose tCG
// needs few iterations (a 3D factor 3-4x the flops of the Euclidean one) keep the first
// factor, long chains (ais2klinik, cheap 2D factors, many iterations) refactor most steps.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/riemannian_preconditioner.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>

namespace tessera {

/// The tangent factor's size predicted from the pose-level pattern of Q alone (an m x m
/// symbolic analysis, AMD; p = d(d+1)/2 coordinates a pose make every pose-level entry a p x p
/// block): a fraction of the cost of the exact analysis (which orders and analyses the mp x mp
/// matrix, supernodally on the 3D graphs: as much as a Euclidean factorization on torus3D).
struct TangentFactorEstimate {
  double entries = 0;  ///< Of the LDL^T factor, p^2 per off-diagonal pose-level entry.
  double flops = 0;    ///< Of one factorization, p^3 x the pose-level factorization's.
  /// The factorization in units of solves with the factor (4 flops an entry each).
  double solves() const { return entries > 0 ? flops / (4.0 * entries) : 0.0; }
};
TangentFactorEstimate estimate_tangent_factor(const BlockProblem& problem);

class CentralizedPreconditioner : public RiemannianPreconditioner {
 public:
  using EuclideanBuilder = std::function<std::unique_ptr<BlockPreconditioner>()>;
  using TangentBuilder = std::function<std::unique_ptr<TangentPreconditioner>()>;

  /// `tangent`: the factored tangent factor, used at rank-d points from the start (may be null
  /// or unusable: then the Euclidean factor is used). `euclidean`: builds the Euclidean factor
  /// on first use. `refresh_ratio` (>= 0): refactor the tangent factor at a new rank-d point
  /// once the solves since the last factorization cost refresh_ratio x a factorization; 0 =
  /// never refactor. Without a tangent factor, `switch_to` (may be empty: never) builds one
  /// (analysed, not factored) once the Euclidean solves at one rank-d point have cost
  /// `switch_flops` (> 0), 4 d flops per entry of the Euclidean factor each; it is then
  /// factored at that point and used from there on.
  CentralizedPreconditioner(std::unique_ptr<TangentPreconditioner> tangent,
                            EuclideanBuilder euclidean, double refresh_ratio,
                            TangentBuilder switch_to = {}, double switch_flops = 0.0);
  ~CentralizedPreconditioner() override;

  /// The tangent factor at rank-d points where it is in use, else the Euclidean one. Not
  /// thread-safe: the trust region calls it from one thread (it refactors and builds lazily).
  Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                        const Eigen::MatrixXd& V) const override;
  /// True once the Euclidean solves at a point have used up the switch budget: the next apply()
  /// factors the tangent factor and uses it.
  bool changes_at_next_apply() const override;

  /// The Euclidean factor (built now if it was not yet).
  const BlockPreconditioner& euclidean() const;
  /// Numeric factorizations of the tangent factor so far (the first one included).
  int tangent_factorizations() const;
  /// True once the Euclidean factor was built.
  bool euclidean_built() const;
  /// True when the Euclidean factor was used at a rank-d point before the tangent factor.
  bool switched() const;
  /// Euclidean-factor solves at rank-d points so far.
  long euclidean_solves() const;

 private:
  bool tangent_in_use() const;

  mutable std::unique_ptr<TangentPreconditioner> tangent_;
  EuclideanBuilder build_euclidean_;
  double refresh_ratio_;
  mutable TangentBuilder switch_to_;  // emptied after the switch (one attempt)
  double switch_flops_;
  mutable std::unique_ptr<BlockPreconditioner> euclidean_;
  // The last rank-d point seen, and the solves done since the last factorization.
  mutable Eigen::MatrixXd point_;
  mutable double solves_since_factor_ = 0;
  // The Euclidean factor at rank-d points: solves at the current point, whether the budget is
  // used up, whether the tangent factor took over.
  mutable long euclidean_solves_at_point_ = 0;
  mutable long euclidean_solves_ = 0;
  mutable bool switch_pending_ = false;
  mutable bool switched_ = false;
};

}  // namespace tessera
