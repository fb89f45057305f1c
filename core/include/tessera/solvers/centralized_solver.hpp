#pragma once
// The centralized certifiable solver (SE-Sync family): chordal initialization, Riemannian
// trust-region on the rank-r relaxation, the minimum-eigenvalue certificate, saddle escape
// up the Riemannian staircase when the certificate fails, and rounding to SE(d). It gives
// the reference optimum f* that distributed runs are measured against.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <tessera/certification/certificate.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/solvers/trust_region.hpp>
#include <vector>

namespace tessera {

enum class Initialization { kChordal, kOdometry, kFile };

/// When the trust region of each staircase level stops (see docs/centralized-solver.md).
enum class CentralizedStop {
  /// The reference solver's rule (SE-Sync's documented defaults, in trust_region's paired-gradient
  /// and relative-decrease fields) plus the same relative-decrease test on the predicted decrease
  /// before a step; or the relative gradient test, whichever comes first. f to ~1e-8 of f*.
  kReference,
  /// Only the relative gradient test (trust_region.grad_norm_tol) and a round-off relative
  /// decrease (1e-14): f* to round-off, for references that other solvers are measured against.
  kGradient,
};

/// Which preconditioner the trust region's tCG uses at rank-d points (see
/// docs/centralized-solver.md; above rank d, after a saddle escape, it is always the Euclidean).
enum class CentralizedPreconditioning {
  /// Chosen per graph (see CentralizedOptions and docs/centralized-solver.md).
  kAuto,
  /// J A^{-1} J^T in tangent coordinates, A = J^T 2Q J + lambda I at the current rotations
  /// (<tessera/solvers/tangent_preconditioner.hpp>): the exact inverse of the Hessian's Q part.
  kTangent,
  /// (2 (Q + lambda I))^{-1} followed by the tangent projection, factored once.
  kEuclidean,
};

struct CentralizedOptions {
  int initial_rank = 5;  ///< r0 >= d. 5 matches the reference optima's runs.
  int max_rank = 10;     ///< Staircase ceiling, >= initial_rank.
  Initialization initialization = Initialization::kChordal;
  bool certify = true;  ///< Run the certificate (and the staircase) after each rank.
  CentralizedStop stop = CentralizedStop::kReference;
  /// Trust-region settings for each staircase level; grad_norm_tol here is relative to
  /// max(1, ||grad f|| at the initial point), so it does not depend on the weights' scale.
  TrustRegionOptions trust_region = default_trust_region();
  CertificateOptions certificate;
  /// Relative diagonal shift of the preconditioner, > 0. 1e-12 rather than 1e-10: on ais2klinik
  /// 1126 instead of 1788 tCG iterations (a long chain: its soft modes sit near the shift), the
  /// other shared graphs within 2 %.
  double preconditioner_shift = 1e-12;
  /// kAuto (the default): per graph, from the tangent factor's symbolic analysis and the tCG
  /// iterations the Euclidean factor needs (the two fields below; docs/centralized-solver.md).
  CentralizedPreconditioning preconditioning = CentralizedPreconditioning::kAuto;
  /// kAuto: start with the tangent factor when its factorization costs at most this many of its
  /// own solves (CHOLMOD's predicted flops against 4 x its entries), else with the Euclidean
  /// factor; finite, >= 0 (0: always start with the Euclidean factor). 30: every 2D shared graph
  /// (at most 21), parking-garage (13), smallGrid3D (24) start with it; torus3D (99),
  /// sphere_bignoise_vertex3 (85), sphere2500 (63), cubicle (57) do not.
  double auto_start_tangent_solves = 30;
  /// kAuto, started with the Euclidean factor: switch to the tangent factor once the Euclidean
  /// solves at one iterate (one step's tCG; 4 d x its entries flops each) cost this fraction of
  /// a tangent factorization; finite, > 0.
  double auto_switch_fraction = 0.2;
  /// kTangent: lambda of A relative to its largest diagonal entry, > 0 (A is singular along the
  /// global translation).
  double tangent_shift = 1e-9;
  /// kTangent: at a new iterate, A is refactored once the solves done with the current factor
  /// cost this many times a factorization (CHOLMOD's predicted flops; >= 0, 0 = factored once at
  /// the start). A stale factor is still a valid preconditioner, merely less exact.
  double tangent_refresh_ratio = 1.0;
  /// kTangent: the factorization is supernodal above this many flops (CHOLMOD's prediction),
  /// simplicial below; > 0.
  double tangent_supernodal_min_flops = 1.5e8;
  /// The preconditioner's factor is supernodal when its factorization takes more than this many
  /// floating-point operations (CHOLMOD's prediction), simplicial otherwise; > 0. The clean
  /// shared graphs need at most 3.6e8 (torus3D; simplicial solves are faster there); graphs with
  /// wrong loop closures between random poses need 1e8-1e11 (city10000 with 25 % random
  /// outliers: 7.9e10, where simplicial factorization is what a robust solve spends its time on).
  /// Only with threads = 1 (the robust solve's weighted and kept-set solves): the factor is then
  /// not computed beside the start, whose own factorizations may call BLAS too.
  double supernodal_min_flops = 5e8;
  /// With threads = 2 and translation elimination: the preconditioner's factorization on the
  /// second thread is supernodal above this many flops (CHOLMOD's prediction; > 0), converted to
  /// simplicial LDL^T for the solves, while the start's and the translations' factorizations on
  /// the first thread are simplicial (no BLAS calls beside the other thread's). 1.5e8: cubicle
  /// (2.3e8 flops) goes supernodal, city10000 (9.7e7) not: there the supernodal factorization
  /// took more instructions (0.79 vs 0.68 G) and its round-off led the tCG one step longer.
  double concurrent_supernodal_min_flops = 1.5e8;
  /// Re-solve the translations exactly for the rotations of every trial point (SE-Sync's
  /// translation elimination; see solvers/translation_elimination.hpp). false: plain
  /// explicit-translation trust region.
  bool eliminate_translations = true;
  /// 1 or 2. With 2, the preconditioner's factorization runs on a second thread while the
  /// start (chordal) is computed; the iterates are the same. The reference solver's bar is its
  /// 2-thread wall on a 2-core machine.
  int threads = 2;
  /// Lanczos tolerance for lambda_min(S) when the factorization test certifies, in (0, 1).
  /// lambda_min is then only reported (the factorization is the proof), and near a certified
  /// optimum the top of the shift-inverted spectrum is a tight cluster that a 1e-8 tolerance
  /// resolves slowly (13 s on ais2klinik vs 0.5 s at 1e-3, which still gives lambda_min to
  /// ~1e-3 eta). A failed test is rerun at certificate.lanczos_tolerance, since the saddle
  /// escape needs an accurate eigenvector.
  double certified_lanczos_tolerance = 1e-3;

  /// The trust-region settings the centralized solver starts from (trust_region's default).
  static TrustRegionOptions default_trust_region();
  /// Throws InputError naming the first field out of range.
  void validate() const;
};

struct StaircaseLevel {
  int rank;
  int iterations;
  double cost;  ///< Relaxation cost f(X) at the end of the level.
  double grad_norm;
  std::optional<double> min_eigenvalue;
  bool certified;
  double elapsed_s;
  /// Why the trust region stopped: grad_norm, preconditioned_grad_norm,
  /// paired_predicted_decrease, predicted_decrease, relative_decrease (the converged ones), or
  /// max_iterations, time, radius.
  std::string stop_reason;
};

struct CentralizedIteration {
  int rank;
  TrustRegionIteration tr;
};

struct CentralizedResult {
  std::vector<Pose> poses;       ///< Rounded estimate in SE(d).
  double cost = 0.0;             ///< Objective of `poses` (reference convention).
  double relaxation_cost = 0.0;  ///< f(X) of the lifted solution (a lower bound when certified).
  double grad_norm = 0.0;        ///< Riemannian gradient norm of the final lifted X.
  int final_rank = 0;
  int iterations = 0;             ///< Trust-region iterations over all levels.
  std::optional<bool> certified;  ///< Empty when certification was off.
  std::optional<double> min_eigenvalue;
  /// The last certificate's weak-duality bound (dual_bound.hpp); NaN fields when none ran.
  DualBound certificate_bound;
  std::vector<StaircaseLevel> levels;
  std::vector<CentralizedIteration> trace;
  /// The preconditioner(s) the trust region used at rank d: "tangent", "euclidean", or
  /// "euclidean,tangent" when kAuto switched from the Euclidean factor to the tangent one.
  std::string preconditioner;
  int inner_iterations = 0;        ///< tCG iterations over all levels.
  int tangent_factorizations = 0;  ///< Numeric factorizations of the tangent factor.
  double init_s = 0.0, optimize_s = 0.0, certify_s = 0.0, total_s = 0.0;
  Eigen::MatrixXd X;  ///< Final lifted solution.

  /// Human-readable multi-line summary.
  std::string full_report() const;
};

/// Solves the graph from options.initialization up the staircase: a trust-region solve per
/// rank, then (when certify is on) the certificate, escaping a saddle one rank up until the
/// certificate holds, max_rank is reached or no escape direction was found. Rounds the last
/// lifted solution to SE(d) and fills every field of the result (trace and timings included;
/// `certified` stays empty when certify is off). Throws InputError when the options are
/// invalid, initial_rank < d, or kFile is asked of a graph without VERTEX lines.
/// `preconditioner_measurements`: null, or the indices of the measurements whose data matrix the
/// trust region's preconditioner factors (any subset that connects the poses; see
/// solvers/preconditioner_edges.hpp). The iterates then differ only through the preconditioner
/// (the tCG's steps and the preconditioned stop tests); the certificate always uses every
/// measurement.
CentralizedResult solve_centralized(
    const PoseGraph& graph, const CentralizedOptions& options = {},
    const std::vector<std::size_t>* preconditioner_measurements = nullptr);

}  // namespace tessera
