#pragma once
// RBCD's round math (Tian et al., Riemannian block coordinate descent): the block update.
// The selected block minimises its local objective over (St(r,d) x R^r)^m with the
// neighbours' poses held fixed, by a few Riemannian trust-region steps (truncated CG,
// preconditioned by a factor computed once per agent: the tangent-coordinate one at rank d,
// else the block's constant Q_BB; docs/irbcd.md section 5).

#include <Eigen/Core>
#include <cstddef>
#include <tessera/problem/block_problem.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>

namespace tessera {

struct BlockUpdateOptions {
  /// Accepted trust-region steps per update (>= 1). RBCD uses 1. With grad_reduction > 0 it
  /// is the most steps an update takes.
  int trust_region_steps = 1;
  /// Adaptive stop of a multi-step update: no further step once the block's Riemannian gradient
  /// norm is at most this fraction of its value at the update's start point (in [0, 1); 0 = off:
  /// always trust_region_steps steps). Only acts with trust_region_steps > 1.
  double grad_reduction = 0.0;
  /// Trust-region iterations tried in total to obtain them; a rejected step shrinks the
  /// radius and retries (>= trust_region_steps).
  int max_attempts = 10;
  int max_inner_iterations = 50;  ///< tCG iterations per step (>= 1).
  double tcg_kappa = 0.1;         ///< tCG linear convergence target, in (0, 1).
  bool precondition = true;       ///< Use a preconditioner (else the identity).
  /// Precondition with the tangent-coordinate factor (solvers/tangent_preconditioner.hpp,
  /// docs/irbcd.md section 5) when the point has rank d (the agents' active rows) and the
  /// factor is not too large or failing; otherwise, and when false, with the Euclidean Q_BB
  /// factor (solvers/block_preconditioner.hpp).
  bool tangent_preconditioner = true;
  /// Updates of an agent between refactorizations of its tangent factor at the current point
  /// (>= 0; 0 = factored once, at the agent's first update, and kept: the basis J(X) is still
  /// taken at every update's point, only A = J^T 2Q_BB J is from the first one).
  int tangent_refresh_interval = 0;
  /// lambda of the tangent factor, relative to the largest diagonal entry of J^T 2Q_BB J (>= 0).
  double tangent_relative_shift = 1e-9;
  /// Floating-point operations of the tangent factorization (CHOLMOD's symbolic prediction)
  /// above which it is computed supernodally (BLAS kernels on its supernodes) and converted to
  /// the simplicial LDL^T form for the solves (>= 0; 0 = always simplicial). Same operator up to
  /// round-off. 1e7: the tangent set-up (analyses and factorization) of torus3D's, sphere2500's
  /// and cubicle's blocks at N = 5 (1.2e7-1.5e8 flops) takes 41-65 % fewer instructions, while
  /// city10000's 2D blocks (4e6-8e6 flops) would take 4 % more (docs/benchmarks/launch_phases.md).
  double tangent_supernodal_min_flops = 1e7;
  /// First trust-region radius of an update preconditioned with the tangent factor, in units
  /// of the preconditioned gradient norm sqrt(<P g, g>) (> 0). That norm is the length of P's
  /// Newton step, so with the (nearly exact) tangent factor a radius of 1 stops tCG on the
  /// boundary after one iteration; 3 lets it converge (sphere_bignoise 257 -> 187 rounds,
  /// cubicle 187 -> 166, docs/irbcd.md section 5). Q_BB-preconditioned updates keep 1: their
  /// norm is inflated by the amplified normal components.
  double tangent_radius_scale = 3.0;
  /// The tangent factor's solves sum their backward dot products as four partial sums instead
  /// of CHOLMOD's one sequential sum (solvers/ldl_chain_solve.hpp): the same solve up to
  /// round-off, with shorter dependency chains (docs/irbcd.md section 8). Only the agents'
  /// block updates use it; the centralized solver's factor keeps CHOLMOD's bits.
  bool tangent_split_dots = true;
  /// Entries of the block's Q_BB Cholesky factor (CHOLMOD's prediction) above which the block
  /// diagonal is used instead, for the updates and the certificate's preconditioner alike
  /// (solvers/block_preconditioner.hpp; 0 = always the exact factor). The default, 16 M entries
  /// (128 MB), bounds an agent's factor memory: 3D grid blocks beyond ~15,000 poses fall back.
  std::size_t max_factor_entries = BlockPreconditioner::kDefaultMaxFactorEntries;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// What a block update did (for the solver's totals).
struct BlockUpdateStats {
  int trust_region_iterations = 0;  ///< Attempts made (accepted or not).
  int tcg_iterations = 0;           ///< Truncated-CG iterations, all attempts.
  bool tangent = false;             ///< Preconditioned with the tangent factor.
  /// problem.cost_share at the returned point (computed with the trust region's cost there).
  double cost_share = 0.0;
};

/// One block update from X0 (on the block's manifold) with the neighbour poses currently set
/// in `problem`. Never increases the local cost: returns X0 when no step is accepted. When
/// `grad_norm_sq` is not null it receives ||grad f_B||^2 at the returned point (the trust-region
/// step computes that gradient anyway; the next status can reuse it). With
/// options.precondition, tCG is preconditioned with `tangent` when it is not null (it must be
/// factored and X0 of rank d: TangentPreconditioner::prepare), else with `preconditioner` (null:
/// the identity). `stats`, when not null, receives what the update did.
Eigen::MatrixXd block_update(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                             const BlockUpdateOptions& options, BlockPreconditioner* preconditioner,
                             double* grad_norm_sq = nullptr,
                             const TangentPreconditioner* tangent = nullptr,
                             BlockUpdateStats* stats = nullptr);

}  // namespace tessera
