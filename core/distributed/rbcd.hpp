#pragma once
// RBCD's round math (Tian et al., Riemannian block coordinate descent): the block update.
// The selected block minimises its local objective over (St(r,d) x R^r)^m with the
// neighbours' poses held fixed, by a few Riemannian trust-region steps (truncated CG,
// preconditioned by the block's constant Q_BB, factored once per agent).

#include <Eigen/Core>

#include "problem/block_problem.hpp"
#include "solvers/block_preconditioner.hpp"

namespace tessera {

struct BlockUpdateOptions {
  /// Accepted trust-region steps per update (>= 1). RBCD uses 1.
  int trust_region_steps = 1;
  /// Trust-region iterations tried in total to obtain them; a rejected step shrinks the
  /// radius and retries (>= trust_region_steps).
  int max_attempts = 10;
  int max_inner_iterations = 50;  ///< tCG iterations per step (>= 1).
  double tcg_kappa = 0.1;         ///< tCG linear convergence target, in (0, 1).
  bool precondition = true;       ///< Use the block's Q_BB factor (else the identity).

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// One block update from X0 (on the block's manifold) with the neighbour poses currently set
/// in `problem`. Never increases the local cost: returns X0 when no step is accepted. When
/// `grad_norm_sq` is not null it receives ||grad f_B||^2 at the returned point (the trust-region
/// step computes that gradient anyway; the next status can reuse it).
Eigen::MatrixXd block_update(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                             const BlockUpdateOptions& options, BlockPreconditioner* preconditioner,
                             double* grad_norm_sq = nullptr);

}  // namespace tessera
