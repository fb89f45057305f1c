// `tessera solve GRAPH --algorithm ALG ...`: optimise a pose graph and report the result.
// The centralized certifiable solver lives here; distributed algorithms are dispatched to
// solve_distributed.cpp.

#include <chrono>
#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "certificate_output.hpp"
#include "commands.hpp"
#include "graph_input.hpp"
#include "json_writer.hpp"
#include "launch/heap_pages.hpp"
#include "launch/heap_retention.hpp"
#include "launch/serial_openmp.hpp"
#include "rebalance_args.hpp"
#include "robust_args.hpp"
#include "solve_distributed.hpp"
#include "solve_online.hpp"
#include "solve_output.hpp"
#include "solver_graph.hpp"
#include "step_coarse_args.hpp"

namespace tessera::cli {
namespace {

const char* kHelp =
    "usage: tessera solve GRAPH --algorithm centralized|rbcd|rbcd++|irbcd [options]\n"
    "\n"
    "Optimises the pose graph GRAPH (g2o, TORO, or dpgo measurement CSV: a .csv file or a\n"
    "folder of robot<k>/measurements.csv) and prints a summary. Written poses are in\n"
    "the input's frame (the FIX pose, else the first pose, keeps its VERTEX value) and ids.\n"
    "\n"
    "  --algorithm centralized   certifiable centralized solver (SE-Sync family): chordal\n"
    "                            initialization, Riemannian trust region, Riemannian staircase\n"
    "                            and a minimum-eigenvalue certificate of global optimality\n"
    "  --out FILE                write the optimised poses (g2o; a name ending in "
    ".tum writes TUM)\n"
    "  --tum FILE                also write the trajectory as TUM text\n"
    "  --json FILE               write a JSON summary ('-' for stdout)\n"
    "  --trace FILE              write one CSV row per solver iteration\n"
    "  --init chordal|odometry|file   initial guess (default chordal; file = VERTEX lines)\n"
    "  --rank R                  initial relaxation rank r0 >= d (default 5)\n"
    "  --max-rank R              staircase ceiling (default 10)\n"
    "  --grad-tol T              relative gradient-norm tolerance (default 1e-6)\n"
    "  --stop reference|gradient  reference (default): also stop where the reference solver's\n"
    "                            rule (gradient 1e-2 with preconditioned gradient 1e-4 or\n"
    "                            with a predicted decrease < 1e-10 f, or a\n"
    "                            step decreasing f by < 1e-7 f while the next is predicted to\n"
    "                            gain < 1e-10 f) holds, or before a step predicted to decrease f\n"
    "                            by < 1e-10 f (ends within ~1e-8 of f*); gradient:\n"
    "                            only --grad-tol (f* to round-off)\n"
    "  --no-certify              skip the certificate (and the staircase). certified = a\n"
    "                            factorization proved a lower bound f_lb on the optimum (weak\n"
    "                            duality, at any point) with f(X) - f_lb <= 1e-4 max(1, |f(X)|);\n"
    "                            JSON: dual_lower_bound, suboptimality_bound (cost - f_lb),\n"
    "                            relative_suboptimality_bound, certificate_grad_norm\n"
    "  --preconditioner auto|tangent|euclidean   centralized: the trust region's\n"
    "                            preconditioner at rank d: tangent = the tangent-coordinate\n"
    "                            factor, euclidean = the factor of Q; auto (default) chooses\n"
    "                            per graph (docs/centralized-solver.md)\n"
    "  --precond-max-flops F     robust centralized: most predicted flops of each solve's\n"
    "                            preconditioner factorization; beyond it the factor keeps the\n"
    "                            known inliers and the highest-weight others that fit; 0 = all\n"
    "                            measurements (docs/robust.md) [1e9]\n"
    "  --gnc-cluster-probes K    robust: most probes after the re-check passes, each cutting\n"
    "                            a run of kept closures side by side at once (or taking back\n"
    "                            one rejected closure near the bound); a probe's result stays\n"
    "                            only if the TLS cost fell; distributed: every agent runs the\n"
    "                            same search, no central step; 0 = none [0]\n"
    "  --raw-quaternions         do not normalise edge quaternions when reading\n";

Initialization parse_init(const std::string& s) {
  if (s == "chordal") return Initialization::kChordal;
  if (s == "odometry") return Initialization::kOdometry;
  if (s == "file") return Initialization::kFile;
  throw InputError("option --init: '" + s + "' is not one of chordal, odometry, file");
}

void write_trace(const std::string& path, const CentralizedResult& r) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot open for writing");
  out << "rank,iteration,cost,grad_norm,radius,rho,inner_iterations,accepted,elapsed_s,"
         "predicted_decrease\n";
  char buf[256];
  for (const auto& row : r.trace) {
    std::snprintf(buf, sizeof buf, "%d,%d,%.17g,%.17g,%.6g,%.6g,%d,%d,%.6f,%.6g\n", row.rank,
                  row.tr.iteration, row.tr.cost, row.tr.grad_norm, row.tr.radius, row.tr.rho,
                  row.tr.inner_iterations, row.tr.accepted ? 1 : 0, row.tr.elapsed_s,
                  row.tr.predicted_decrease);
    out << buf;
  }
}

int solve_centralized_command(const Arguments& a, const std::string& graph_path,
                              const RobustOptions& robust,
                              std::chrono::steady_clock::time_point start) {
  G2oReadOptions read;
  read.normalize_quaternions = !a.has("raw-quaternions");
  const LoadedGraph input = load_graph(a, graph_path, read);
  const PoseGraph& graph = input.graph;
  CentralizedOptions opt;
  // A robust solve's first plain solve starts from the cheaper, in TLS cost, of the chordal
  // guess and the known inliers' start (GncCentralizedOptions::known_inlier_start): the chordal
  // guess is a least-squares fit of every edge, outliers included, and the plain solve from
  // there settles where GNC rejects true edges too (intel, 25 % random outliers: 121 rejected
  // for 64 wrong); the odometry chain's drift on clean data leads it to a critical point whose
  // residuals GNC cuts (cubicle: 3 true edges).
  opt.initialization = parse_init(a.get_or("init", "chordal"));
  opt.initial_rank = static_cast<int>(a.get_long("rank", opt.initial_rank));
  opt.max_rank = static_cast<int>(a.get_long("max-rank", std::max(opt.max_rank, opt.initial_rank)));
  opt.trust_region.grad_norm_tol = a.get_double("grad-tol", opt.trust_region.grad_norm_tol);
  opt.certify = !a.has("no-certify");
  const std::string stop = a.get_or("stop", "reference");
  if (stop == "gradient")
    opt.stop = CentralizedStop::kGradient;
  else if (stop != "reference")
    throw InputError("option --stop: '" + stop + "' is not one of reference, gradient");
  const std::string precon = a.get_or("preconditioner", "auto");
  if (precon == "tangent")
    opt.preconditioning = CentralizedPreconditioning::kTangent;
  else if (precon == "euclidean")
    opt.preconditioning = CentralizedPreconditioning::kEuclidean;
  else if (precon == "auto")
    opt.preconditioning = CentralizedPreconditioning::kAuto;
  else
    throw InputError("option --preconditioner: '" + precon +
                     "' is not one of auto, tangent, euclidean");
  GncCentralizedResult gnc;
  if (robust.kind != RobustKind::kNone) {
    GncCentralizedOptions gnc_options;
    gnc_options.solver = opt;
    gnc_options.robust = robust;
    gnc_options.known_inlier_flags = input.known_inlier;
    gnc_options.preconditioner.max_flops =
        a.get_double("precond-max-flops", gnc_options.preconditioner.max_flops);
    try {
      gnc_options.preconditioner.validate();
    } catch (const InputError& e) {
      throw InputError(std::string("option --precond-max-flops: ") + e.what());
    }
    gnc_options.cluster_probes =
        static_cast<int>(a.get_long("gnc-cluster-probes", gnc_options.cluster_probes));
    if (gnc_options.cluster_probes < 0)
      throw InputError("option --gnc-cluster-probes: GncCentralizedOptions.cluster_probes = " +
                       std::to_string(gnc_options.cluster_probes) + ": must be >= 0 (0 = none)");
    gnc = solve_gnc_centralized(graph, gnc_options);
  } else
    gnc.final_solve = solve_centralized(graph, opt);
  const CentralizedResult& r = gnc.final_solve;
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("%s", r.full_report().c_str());
  std::printf("%s: %zu poses, %zu edges, d = %d: cost %.10g, %s, %.3f s\n", graph_path.c_str(),
              graph.num_poses, graph.num_measurements(), graph.d, r.cost,
              r.certified ? (*r.certified ? "certified optimal" : "NOT certified")
                          : "not certified (skipped)",
              wall_s);
  if (r.certified) std::printf("%s", certificate_bound_line(r.certificate_bound, r.cost).c_str());
  RobustSummary robust_summary;
  robust_summary.options = robust;
  robust_summary.outer_iterations = gnc.outer_iterations;
  robust_summary.total_iterations = gnc.inner_iterations;
  if (robust.kind != RobustKind::kNone) robust_summary.total_cg_iterations = gnc.cg_iterations;
  robust_summary.measurements = graph.num_measurements();
  robust_summary.rejected = gnc.rejected;
  robust_summary.threshold_squared = gnc.threshold_squared;
  robust_summary.weights_converged = gnc.weights_converged;
  robust_summary.readmitted = gnc.readmitted;
  robust_summary.probes = gnc.probes;
  robust_summary.probes_kept = gnc.probes_kept;
  if (robust.kind != RobustKind::kNone) {
    robust_summary.swap_probes = gnc.swap_probes;
    robust_summary.swap_probes_kept = gnc.swap_probes_kept;
  }
  if (robust.kind != RobustKind::kNone)
    std::printf(
        "robust %s: %d outer steps, %zu of %zu measurements rejected, cost over the "
        "kept ones\n",
        robust_kind_name(robust.kind), gnc.outer_iterations, gnc.rejected.size(),
        graph.num_measurements());
  // Each solve's truncated-CG work against its preconditioner's predicted factorization flops.
  double precond_flops = 0, full_flops = 0;
  for (const GncSolveWork& w : gnc.solves) {
    std::printf(
        "  solve: %d trust-region / %d CG iterations, preconditioner %zu of %zu measurements, "
        "%.3g flops (all: %.3g)\n",
        w.trust_region_iterations, w.cg_iterations, w.preconditioner_measurements, w.measurements,
        w.preconditioner_flops, w.full_flops);
    precond_flops += w.preconditioner_flops;
    full_flops += w.full_flops;
  }
  if (auto p = a.get("rejected")) write_rejected(*p, gnc.rejected);
  write_solution_files(a, graph, input.keys, r.poses);
  if (auto p = a.get("trace")) write_trace(*p, r);
  if (auto p = a.get("json")) {
    SolveSummary summary;
    summary.algorithm = "centralized";
    summary.rank = r.final_rank;
    summary.iterations = r.iterations;
    summary.grad_norm = r.grad_norm;
    summary.cost = r.cost;
    summary.relaxation_cost = r.relaxation_cost;
    summary.certified = r.certified;
    JsonObject j = solve_json(graph_path, graph, summary);
    if (robust.kind != RobustKind::kNone) {
      add_robust_fields(j, robust_summary);
      j.add("precond_flops", precond_flops).add("precond_full_flops", full_flops);
    }
    j.add("min_eigenvalue", r.min_eigenvalue);
    if (r.certified) add_certificate_bound(j, r.certificate_bound, r.cost);
    j.add("final_rank", r.final_rank)
        .add("stop_reason", r.levels.empty() ? std::string() : r.levels.back().stop_reason)
        .add("preconditioner", r.preconditioner)
        .add("inner_iterations", r.inner_iterations)
        .add("tangent_factorizations", r.tangent_factorizations)
        .add("init_s", r.init_s)
        .add("optimize_s", r.optimize_s)
        .add("certify_s", r.certify_s)
        .add("solve_s", r.total_s)
        .add("wall_s", wall_s);
    write_output(*p, j.str());
  }
  return 0;
}

}  // namespace

int run_solve(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  std::set<std::string> valued = {"algorithm", "out",      "tum",      "json",    "trace", "init",
                                  "rank",      "max-rank", "grad-tol", "tum-dir", "stop"};
  valued.insert("preconditioner");
  for (const char* const* o = kGraphInputOptions; *o; ++o) valued.insert(*o);
  std::set<std::string> switches = {"help", "no-certify", "raw-quaternions"};
  for (const char* const* o = kDistributedValued; *o; ++o) valued.insert(*o);
  for (const char* const* o = kDistributedSwitches; *o; ++o) switches.insert(*o);
  for (const char* const* o = kOnlineValued; *o; ++o) valued.insert(*o);
  for (const char* const* o = kOnlineSwitches; *o; ++o) switches.insert(*o);
  for (const char* const* o = kRebalanceValued; *o; ++o) valued.insert(*o);
  for (const char* const* o = kRebalanceSwitches; *o; ++o) switches.insert(*o);
  for (const char* const* o = kStepCoarseValued; *o; ++o) valued.insert(*o);
  for (const char* const* o = kRobustValued; *o; ++o) valued.insert(*o);
  valued.insert("precond-max-flops");
  valued.insert("gnc-cluster-probes");
  valued.insert("heap-pages");
  Arguments a(args, valued, switches);
  if (a.has("help")) {
    std::printf("%s%s%s%s%s%s%s%s%s", kHelp, kHeapPagesHelp, kSolutionOutputHelp, kGraphInputHelp,
                kDistributedHelp, kOnlineHelp, kStepCoarseHelp, kRebalanceHelp, kRobustHelp);
    return 0;
  }
  if (a.positional().size() != 1)
    throw InputError("expected exactly one GRAPH argument (see tessera solve --help)");
  // Before the solve allocates: this may re-run the process on huge-page heaps.
  launch::enter_heap_pages(
      launch::parse_heap_pages(a.get_or("heap-pages", "auto"), "option --heap-pages"));
  // Every algorithm's CHOLMOD factorizations run on the solver's own threads, as in the agent
  // processes: CHOLMOD's OpenMP teams of 4 parallelise only its supernodal factorization's
  // zeroing and scattering loops (the BLAS is serial), so on these problems they added
  // fork/join and spin-waiting, not speed (launch/serial_openmp.hpp, docs/decisions.md). Same bits.
  launch::serial_openmp();
  if (a.has("online")) {
    // Freed heap kept for the next step, as in the agent processes (launch/heap_retention.hpp):
    // every step builds the grown blocks' factors again and every CG iteration's messages are
    // copied, and with glibc's default thresholds those freed blocks went back to the kernel and
    // were faulted in again (the 5,000-pose grid's online run: 72-84k minor faults and 0.9-1.3
    // s of system time against 32k and 0.4-0.5 s; docs/online.md). Same bits.
    launch::retain_freed_heap();
    return solve_online_command(a, a.positional()[0], start);
  }
  const std::string algorithm = a.get_or("algorithm", "centralized");
  const RobustOptions robust = parse_robust_options(a);
  if (algorithm == "centralized")
    return solve_centralized_command(a, a.positional()[0], robust, start);
  if (algorithm == "rbcd" || algorithm == "rbcd++" || algorithm == "irbcd")
    return solve_distributed_command(a, a.positional()[0], robust, start);
  throw InputError("option --algorithm: '" + algorithm +
                   "' is not one of centralized, rbcd, rbcd++, irbcd");
}

}  // namespace tessera::cli
