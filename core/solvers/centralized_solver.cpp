#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <sstream>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/solvers/translation_elimination.hpp>
#include <tessera/util/input_error.hpp>

#include "solvers/centralized_preconditioner.hpp"

namespace tessera {

TrustRegionOptions CentralizedOptions::default_trust_region() {
  TrustRegionOptions o;
  o.max_iterations = 500;
  o.max_inner_iterations = 2000;
  // Relative to max(1, the start's gradient norm). 1e-6: with the tangent preconditioner a step
  // costs few tCG iterations, and 1e-5 stopped ais2klinik (first gradient 281) 1.6e-8 above f*
  // (the reference: 1.9e-9); 1e-6 ends it at 1.4e-9 for one more step (74 -> 108 tCG iterations).
  o.grad_norm_tol = 1e-6;
  // The reference solver's stopping rule (SE-Sync's documented defaults): a gradient below 1e-2
  // together with a preconditioned gradient (about the Newton step) below 1e-4, or an accepted
  // step that decreased f by little (the reference: 1e-6 of f) or whose rotation part is
  // shorter than 1e-3.
  o.paired_grad_norm_tol = 1e-2;
  o.preconditioned_grad_norm_tol = 1e-4;
  // 1e-7 instead of the reference's 1e-6: on ais2klinik, a long chain, a step of 2.6e-7 f left
  // 1.6e-8 f (the prediction below, without the Hessian's multiplier term, is low there).
  o.rel_cost_decrease_tol = 1e-7;
  // The same gradient bound paired with the predicted decrease 1/2 <P g, g>. With the tangent
  // preconditioner P is the inverse of the Hessian's Q part and the prediction is close to the
  // remaining gap (the Euclidean factor overstated it 0.3-50x, which the former 1e-6 / 1e-8
  // allowed for): 1e-10, so that every shared graph ends at least as close to f* as the
  // reference (CSAIL, MIT and manhattan3500 ended 1.2-1.7e-8 above f* at 1e-6 / 1e-8).
  o.paired_predicted_rel_decrease_tol = 1e-10;
  // Its fourth test, an accepted step's norm below 1e-3, is left out: on small graphs (40 poses)
  // such a step still moves f by 1e-6 of f.
  // The relative-decrease test taken before the step on the predicted decrease, so the step that
  // would only confirm convergence is not computed (see above for 1e-10).
  o.predicted_rel_decrease_tol = 1e-10;
  // The forcing terms below were measured with the Euclidean preconditioner.
  // Once the gradient is below 1e-2 of its start, the tCG forcing term tightens to SE-Sync's 0.1:
  // each of the last, costliest steps then gains more (13 of the 16 shared graphs end at least as
  // close to f* as the reference, 7 with 0.3 throughout, for 0-12 % more tCG iterations). Far
  // from the optimum 0.3 stays (below: 0.1 there took ais2klinik 13 steps, 2758 tCG iterations).
  o.tcg_kappa_near = 0.1;
  o.near_relative_grad = 1e-2;
  // Forcing term min(kappa, |r0|^theta) of the inner CG: theta = 0.5 instead of 1 keeps the
  // final steps' CG from solving to |g|^2 accuracy (1299 -> 451 iterations for the last step
  // on ais2klinik) while staying superlinear.
  o.tcg_theta = 0.5;
  // Linear forcing 0.3 instead of 0.1: shorter early steps that land inside the region. On
  // ais2klinik 6 outer / 1623 tCG iterations, no rejected step (vs 11 / 3262, 4 rejected);
  // on the easy graphs it costs 10-40% more CPU, all far below the reference there.
  o.tcg_kappa = 0.3;
  return o;
}

void CentralizedOptions::validate() const {
  if (initial_rank < 2) throw InputError("CentralizedOptions.initial_rank must be >= d (2 or 3)");
  if (max_rank < initial_rank)
    throw InputError("CentralizedOptions.max_rank must be >= initial_rank");
  if (!(certified_lanczos_tolerance > 0 && certified_lanczos_tolerance < 1))
    throw InputError("CentralizedOptions.certified_lanczos_tolerance must be in (0, 1)");
  if (!(supernodal_min_flops > 0))
    throw InputError("CentralizedOptions.supernodal_min_flops must be > 0");
  if (!(concurrent_supernodal_min_flops > 0))
    throw InputError("CentralizedOptions.concurrent_supernodal_min_flops must be > 0");
  if (!(preconditioner_shift > 0))
    throw InputError("CentralizedOptions.preconditioner_shift must be > 0");
  if (!(tangent_shift > 0)) throw InputError("CentralizedOptions.tangent_shift must be > 0");
  if (!(tangent_refresh_ratio >= 0 && std::isfinite(tangent_refresh_ratio)))
    throw InputError("CentralizedOptions.tangent_refresh_ratio must be finite and >= 0");
  if (!(tangent_supernodal_min_flops > 0))
    throw InputError("CentralizedOptions.tangent_supernodal_min_flops must be > 0");
  if (!(auto_start_tangent_solves >= 0 && std::isfinite(auto_start_tangent_solves)))
    throw InputError("CentralizedOptions.auto_start_tangent_solves must be finite and >= 0");
  if (!(auto_switch_fraction > 0 && std::isfinite(auto_switch_fraction)))
    throw InputError("CentralizedOptions.auto_switch_fraction must be finite and > 0");
  if (threads < 1 || threads > 2) throw InputError("CentralizedOptions.threads must be 1 or 2");
  trust_region.validate();
  certificate.validate();
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::vector<Pose> odometry_initialization(const PoseGraph& graph) {
  // Compose consecutive-id measurements; poses not reachable that way start at identity.
  std::vector<Pose> poses(graph.num_poses, Pose::identity(graph.d));
  std::vector<const Measurement*> next(graph.num_poses, nullptr);
  for (const auto& m : graph.measurements)
    if (m.j == m.i + 1 && !next[m.i]) next[m.i] = &m;
  for (std::size_t i = 0; i + 1 < graph.num_poses; ++i) {
    if (!next[i]) continue;
    poses[i + 1].R = poses[i].R * next[i]->R;
    poses[i + 1].t = poses[i].t + poses[i].R * next[i]->t;
  }
  return poses;
}

// Escapes a saddle at rank r along the negative-curvature direction v (eigenvector of S).
// Returns the new point at rank r+1.
// The new point must not meet a gradient stop of `tr` at once (it would end the next level where
// it starts).
Eigen::MatrixXd escape_saddle(const BlockProblem& problem, const Eigen::MatrixXd& X,
                              const Eigen::VectorXd& v, const TrustRegionOptions& tr,
                              const RiemannianPreconditioner& precon) {
  Eigen::MatrixXd Xa = pad_rank(X, 1);
  Eigen::MatrixXd dir = Eigen::MatrixXd::Zero(Xa.rows(), Xa.cols());
  dir.row(Xa.rows() - 1) = v.transpose();  // tangent at Xa: Xa's last row is zero
  const LiftedManifold M = problem.manifold(static_cast<int>(Xa.rows()));
  const double f0 = problem.cost(Xa);
  double alpha = 1e2 * std::sqrt(static_cast<double>(problem.num_owned()));
  for (int k = 0; k < 80; ++k, alpha *= 0.5) {
    Eigen::MatrixXd Xp = M.retract(Xa, alpha * dir);
    if (problem.cost(Xp) >= f0) continue;
    Eigen::MatrixXd g = M.tangent_project(Xp, problem.euclidean_gradient(Xp));
    if (g.norm() <= tr.grad_norm_tol) continue;
    if (tr.paired_grad_norm_tol <= 0 || g.norm() > tr.paired_grad_norm_tol) return Xp;
    const Eigen::MatrixXd Pg = precon.apply(M, Xp, g);
    const bool paired_norm =
        tr.preconditioned_grad_norm_tol > 0 && Pg.norm() <= tr.preconditioned_grad_norm_tol;
    const bool paired_decrease =
        tr.paired_predicted_rel_decrease_tol > 0 &&
        0.5 * Pg.cwiseProduct(g).sum() <= tr.paired_predicted_rel_decrease_tol * problem.cost(Xp);
    if (!paired_norm && !paired_decrease) return Xp;
  }
  throw std::runtime_error("saddle escape: no descent step found along the eigenvector");
}

}  // namespace

CentralizedResult solve_centralized(const PoseGraph& graph, const CentralizedOptions& options,
                                    const std::vector<std::size_t>* preconditioner_measurements) {
  options.validate();
  if (options.initial_rank < graph.d)
    throw InputError("CentralizedOptions.initial_rank must be >= d = " + std::to_string(graph.d));
  const auto start = Clock::now();
  CentralizedResult res;

  const BlockProblem problem =
      BlockProblem::whole_graph(graph.d, graph.num_poses, graph.measurements);
  // Always the exact factor, and simplicial LDL^T unless the factorization is dense
  // (supernodal_min_flops): its solves with r right-hand sides are what the tCG repeats
  // (docs/centralized-solver.md). The distributed blocks' switch to supernodal above 1 M entries
  // made cubicle's and city10000's whole-graph factors supernodal: CPU in alternated pairs (load
  // 7-8) cubicle 1.41/1.80/2.50 s simplicial vs 1.67/1.99/2.28 s, city10000 1.28/1.12/1.18 vs
  // 1.39/1.84/1.41.
  // A supernodal factorization calls BLAS, and the serial OpenBLAS build has no locks for
  // concurrent calls. With two threads and translation elimination the preconditioner's
  // factorization (second thread) is supernodal above concurrent_supernodal_min_flops and
  // converted to simplicial LDL^T for the solves, while the start's and the translations'
  // factorizations (first thread) are simplicial: cubicle's preconditioner 1.35 -> 0.57 G
  // instructions, the chordal start 0.36 -> 0.69 G, so the first thread no longer waits.
  // Otherwise (one thread, or explicit translations, whose start may factor supernodally
  // meanwhile) the flops rule applies only on one thread.
  const bool concurrent = options.threads > 1 && options.eliminate_translations;
  const double supernodal_min_flops =
      concurrent ? options.concurrent_supernodal_min_flops
                 : (options.threads > 1 ? 0.0 : options.supernodal_min_flops);
  // A preconditioner on a subset of the measurements has its own data matrix; the trust region
  // and the certificate keep the whole problem.
  std::optional<BlockProblem> subset_problem;
  if (preconditioner_measurements) {
    std::vector<Measurement> kept;
    kept.reserve(preconditioner_measurements->size());
    for (std::size_t e : *preconditioner_measurements) kept.push_back(graph.measurements.at(e));
    subset_problem = BlockProblem::whole_graph(graph.d, graph.num_poses, kept);
  }
  const BlockProblem& precon_problem = subset_problem ? *subset_problem : problem;
  const auto build_preconditioner = [&precon_problem, &options, supernodal_min_flops, concurrent] {
    return std::make_unique<BlockPreconditioner>(precon_problem, options.preconditioner_shift, 0, 0,
                                                 supernodal_min_flops, concurrent);
  };
  // Which factor the trust region starts with. kAuto decides from the tangent factor's size
  // predicted from the pose-level pattern (estimate_tangent_factor: an m x m symbolic analysis,
  // cheap beside the exact one): its factorization in units of its own solves. Up to
  // auto_start_tangent_solves it is built at once: even a graph whose Euclidean factor needs
  // few tCG iterations then loses no more than that many solves (every 2D shared graph,
  // parking-garage, smallGrid3D). Above it (the denser 3D graphs: torus3D, sphere2500,
  // sphere_bignoise_vertex3, cubicle) the trust region starts with the Euclidean factor and
  // switches to the tangent one when a step's tCG shows that it needs many iterations
  // (auto_switch_fraction; solvers/centralized_preconditioner.hpp).
  const CentralizedPreconditioning mode = options.preconditioning;
  const auto analyse_tangent = [&problem, &options] {
    return std::make_unique<TangentPreconditioner>(problem, options.tangent_shift, 0,
                                                   options.tangent_supernodal_min_flops);
  };
  struct Setup {
    std::unique_ptr<TangentPreconditioner>
        tangent;  // analysed when the trust region starts with it
    std::unique_ptr<BlockPreconditioner> euclidean;  // built when the trust region starts with it
    double switch_flops = 0;                         // kAuto started with the Euclidean factor
  };
  const auto setup = [&] {
    Setup out;
    bool tangent_first = mode == CentralizedPreconditioning::kTangent;
    if (mode == CentralizedPreconditioning::kAuto) {
      const TangentFactorEstimate estimate = estimate_tangent_factor(problem);
      tangent_first = estimate.solves() <= options.auto_start_tangent_solves;
      out.switch_flops = options.auto_switch_fraction * estimate.flops;
    }
    if (tangent_first) {
      out.tangent = analyse_tangent();
      out.switch_flops = 0;
    } else {
      out.euclidean = build_preconditioner();
    }
    return out;
  };
  // The analysis and the Euclidean factorization do not depend on the start: with a second
  // thread they run while the start is computed (each CHOLMOD factor has its own workspace, so
  // the two do not share state). The tangent factor needs the start's rotations; it is
  // factored below.
  std::future<Setup> pending;
  if (options.threads > 1) pending = std::async(std::launch::async, setup);
  std::vector<Pose> init;
  switch (options.initialization) {
    case Initialization::kChordal:
      // With translation elimination the trust region replaces the start's translations by
      // their exact minimiser before its first step (the same weighted Laplacian solve), so
      // the chordal start's own translation solve would be done twice.
      init = options.eliminate_translations
                 ? assemble_poses(chordal_rotations(graph, concurrent),
                                  Eigen::MatrixXd::Zero(graph.d, graph.num_poses))
                 : chordal_initialization(graph);
      break;
    case Initialization::kOdometry:
      init = odometry_initialization(graph);
      break;
    case Initialization::kFile:
      if (!graph.has_initial())
        throw InputError(graph.source, 0, "has no VERTEX lines to initialise from");
      init = graph.initial;
      break;
  }
  Setup ready = pending.valid() ? pending.get() : setup();
  // The tangent factor depends on the start's rotations only: with a second thread and
  // translation elimination it is computed beside the elimination's (simplicial) Laplacian
  // factorization.
  std::future<void> pending_tangent;
  const auto factor_tangent = [&ready](Eigen::MatrixXd X0) {
    if (ready.tangent->usable()) ready.tangent->factorize(X0);
  };
  if (ready.tangent && concurrent)
    pending_tangent = std::async(std::launch::async, factor_tangent, lift_poses(init, graph.d));
  std::unique_ptr<TranslationElimination> elimination;
  PointRefinement refine;
  if (options.eliminate_translations) {
    elimination = std::make_unique<TranslationElimination>(graph.d, graph.num_poses,
                                                           graph.measurements, concurrent);
    refine = [&elimination](Eigen::MatrixXd& Y) { elimination->optimize_translations(Y); };
  }
  if (ready.tangent) {
    if (pending_tangent.valid())
      pending_tangent.get();
    else
      factor_tangent(lift_poses(init, graph.d));
  }
  std::unique_ptr<BlockPreconditioner> precon_factor = std::move(ready.euclidean);
  // Above rank d (after an escape), or if the tangent factor failed, the Euclidean factor is
  // built when first needed; nothing else runs then, so it may be supernodal and converted.
  CentralizedPreconditioner precon(
      std::move(ready.tangent),
      [&problem, &options, &precon_factor]() {
        if (precon_factor) {
          std::unique_ptr<BlockPreconditioner> out;
          out.swap(precon_factor);
          return out;
        }
        return std::make_unique<BlockPreconditioner>(problem, options.preconditioner_shift, 0, 0,
                                                     options.concurrent_supernodal_min_flops, true);
      },
      mode != CentralizedPreconditioning::kEuclidean ? options.tangent_refresh_ratio : 0.0,
      ready.switch_flops > 0 ? CentralizedPreconditioner::TangentBuilder(analyse_tangent)
                             : CentralizedPreconditioner::TangentBuilder(),
      ready.switch_flops);
  // Only the rows of X that can be non-zero are stored ("active rows"). The lifted initial
  // guess [I_d; 0] R has r - d zero rows, and the trust region keeps them exactly zero (the
  // gradient, the Hessian, the row-wise preconditioner, the tangent projection and the polar
  // retraction all map zero rows to zero rows), so iterating on the d active rows computes
  // exactly the rank-r iterates at d/r of the cost. The certificate depends on X only through
  // its active rows, and a saddle is escaped into a new row, which is one of the zero rows
  // while fewer than r are active; the reported rank is max(r0, active rows).
  Eigen::MatrixXd X = lift_poses(init, graph.d);
  res.init_s = seconds_since(start);

  TrustRegionOptions tr = options.trust_region;
  if (options.stop == CentralizedStop::kGradient) {
    tr.paired_grad_norm_tol = 0;
    tr.preconditioned_grad_norm_tol = 0;
    tr.paired_predicted_rel_decrease_tol = 0;
    tr.predicted_rel_decrease_tol = 0;
    tr.step_norm_tol = 0;
    tr.rel_cost_decrease_tol = std::min(tr.rel_cost_decrease_tol, 1e-14);
  }
  {
    // The relative tolerance is measured at the start the trust region sees: with elimination
    // its translations are the exact ones (the chordal start above has none yet).
    if (refine) refine(X);
    const LiftedManifold M = problem.manifold(graph.d);
    const double g0 = M.tangent_project(X, problem.euclidean_gradient(X)).norm();
    tr.grad_norm_tol = options.trust_region.grad_norm_tol * std::max(1.0, g0);
  }
  for (;;) {
    const int active = static_cast<int>(X.rows());
    const int r = std::max(options.initial_rank, active);
    const auto level_start = Clock::now();
    TrustRegionResult level =
        solve_trust_region(problem, X, tr, &precon, refine ? &refine : nullptr);
    res.optimize_s += seconds_since(level_start);
    X = level.X;
    res.iterations += level.iterations;
    res.inner_iterations += level.total_inner_iterations;
    for (const auto& it : level.trace) res.trace.push_back({r, it});
    StaircaseLevel info{
        r,     level.iterations,           level.cost,       level.grad_norm, std::nullopt,
        false, seconds_since(level_start), level.stop_reason};
    res.final_rank = r;
    res.relaxation_cost = level.cost;
    res.grad_norm = level.grad_norm;
    if (!options.certify) {
      res.levels.push_back(info);
      break;
    }
    const auto cert_start = Clock::now();
    CertificateOptions quick = options.certificate;
    quick.lanczos_tolerance =
        std::max(options.certificate.lanczos_tolerance, options.certified_lanczos_tolerance);
    CertificateResult cert = verify_certificate(problem, X, quick);
    if (!cert.psd_within_tolerance &&
        quick.lanczos_tolerance > options.certificate.lanczos_tolerance)
      cert = verify_certificate(problem, X, options.certificate);
    res.certify_s += seconds_since(cert_start);
    info.min_eigenvalue = cert.min_eigenvalue;
    // S(X) >= 0 proves optimality only at a first-order critical point: a level that ran out
    // of iterations or time is not certified, whatever the eigenvalue says.
    const bool converged =
        level.stop_reason == "grad_norm" || level.stop_reason == "preconditioned_grad_norm" ||
        level.stop_reason == "paired_predicted_decrease" ||
        level.stop_reason == "predicted_decrease" || level.stop_reason == "relative_decrease" ||
        level.stop_reason == "step_norm";
    info.certified = cert.certified && converged;
    info.elapsed_s = seconds_since(level_start);
    res.levels.push_back(info);
    res.certified = info.certified;
    res.min_eigenvalue = cert.min_eigenvalue;
    res.certificate_bound = cert.bound;
    // No eigenvector (Lanczos did not converge): nothing to escape along.
    if (cert.certified || active >= options.max_rank || cert.min_eigenvector.size() == 0) break;
    X = escape_saddle(problem, X, cert.min_eigenvector, tr, precon);
  }
  // Report X at the relaxation rank: the rows that were never active are zero.
  if (X.rows() < res.final_rank) X = pad_rank(X, res.final_rank - static_cast<int>(X.rows()));
  res.X = X;
  res.tangent_factorizations = precon.tangent_factorizations();
  res.preconditioner = precon.switched()                ? "euclidean,tangent"
                       : res.tangent_factorizations > 0 ? "tangent"
                                                        : "euclidean";
  if (elimination) {
    // The rounded rotations' optimal translations through the factor computed once above
    // (round_solution would build and factor the same Laplacian again).
    const Eigen::MatrixXd R = round_rotations(X, graph.d);
    Eigen::MatrixXd rounded =
        lift_poses(assemble_poses(R, Eigen::MatrixXd::Zero(graph.d, graph.num_poses)), graph.d);
    elimination->optimize_translations(rounded);
    res.poses = assemble_poses(R, Eigen::MatrixXd::Zero(graph.d, graph.num_poses));
    for (std::size_t i = 0; i < graph.num_poses; ++i)
      res.poses[i].t = rounded.col((graph.d + 1) * static_cast<Eigen::Index>(i) + graph.d);
  } else {
    res.poses = round_solution(graph, X);
  }
  res.cost = evaluate_objective(graph, res.poses);
  res.certified = estimate_certified(res.certified, res.cost, res.relaxation_cost);
  res.total_s = seconds_since(start);
  return res;
}

std::string CentralizedResult::full_report() const {
  std::ostringstream os;
  os.precision(12);
  os << "Centralized certifiable solve\n";
  for (const auto& l : levels) {
    os << "  rank " << l.rank << ": " << l.iterations << " iterations, f(X) = " << l.cost
       << ", |grad| = " << l.grad_norm;
    if (l.min_eigenvalue)
      os << ", lambda_min(S) = " << *l.min_eigenvalue
         << (l.certified ? " (certified)" : " (saddle)");
    os << ", stop: " << l.stop_reason << ", " << l.elapsed_s << " s\n";
  }
  os << "  rounded cost " << cost << " (relaxation " << relaxation_cost << ")\n";
  os << "  certified: " << (certified ? (*certified ? "yes" : "no") : "not checked");
  if (certified && !*certified && !levels.empty() && levels.back().certified)
    os << " (relaxation certified but not tight: the rounded cost is "
       << relative_rounding_gap(cost, relaxation_cost) << " relative above f(X))";
  os << "\n";
  os << "  time: init " << init_s << " s, optimize " << optimize_s << " s, certify " << certify_s
     << " s, total " << total_s << " s\n";
  return os.str();
}

}  // namespace tessera
