#include "solve_distributed.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>
#include <tessera/certification/certificate_cap.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/partition/robot_partition.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "certificate_output.hpp"
#include "graph_input.hpp"
#include "json_writer.hpp"
#include "partition_file.hpp"
#include "robust_args.hpp"
#include "run_wide_args.hpp"
#include "solve_output.hpp"
#include "solver_graph.hpp"
#include "step_coarse_args.hpp"

namespace tessera::cli {

const char* const kDistributedValued[] = {"agents",
                                          "partition",
                                          "max-rounds",
                                          "seed",
                                          "reference-cost",
                                          "select",
                                          "rel-tol",
                                          "tr-steps",
                                          "tr-grad-reduction",
                                          "irbcd-tr-steps",
                                          "irbcd-grad-reduction",
                                          "restart-c",
                                          "sigma",
                                          "unselected",
                                          "irbcd-n",
                                          "tcg-iters",
                                          "robots",
                                          "certify-grad-tol",
                                          "certify-iters",
                                          "certify-residual",
                                          "certify-precon",
                                          "certify-interface",
                                          "certify-interface-sides",
                                          "block-precon",
                                          "tangent-refresh",
                                          "tcg-kappa",
                                          "sigma-shrink",
                                          "sigma-saturation",
                                          "sigma-theta",
                                          "sigma-min",
                                          "sigma-max",
                                          "irbcd-a0",
                                          "tangent-radius",
                                          "tangent-dots",
                                          "irbcd-class-score",
                                          "partition-objective",
                                          "partition-time",
                                          "partition-file",
                                          "coarse",
                                          "coarse-every",
                                          "coarse-min-gain",
                                          "coarse-space",
                                          "coarse-aggregates",
                                          "coarse-smoothing",
                                          "refine",
                                          "refine-grad-tol",
                                          "refine-cg-iters",
                                          "refine-rel-tol",
                                          "refine-coarse",
                                          "refine-coarse-form",
                                          "refine-coarse-aggregates",
                                          "refine-interface",
                                          "refine-translation-interface",
                                          "refine-gauge",
                                          "refine-sigma",
                                          nullptr};
const char* const kDistributedSwitches[] = {"parallel",      "sequential",  "reference",
                                            "certify",       "sigma-adapt", "sigma-fixed",
                                            "irbcd-keep-ab", nullptr};

const char* kDistributedHelp =
    "\n"
    "Distributed algorithms (N agents in one process, same messages as over DDS):\n"
    "  --algorithm rbcd|rbcd++|irbcd   RBCD, Nesterov-accelerated RBCD++, or IRBCD (default "
    "algorithm\n"
    "                            of the reference paper; see docs/irbcd.md)\n"
    "  --agents N                number of agents / blocks (default 5)\n"
    "  --partition PRESET        auto|sequential|fast|eco|strong|highest (default auto: fast\n"
    "                            below 2000 poses, where the run is short and fast needs\n"
    "                            the same rounds, else eco; strong, highest search far\n"
    "                            longer for a few % less cut)\n"
    "  --partition-objective cut|rounds   rounds (default): after the preset's search, a\n"
    "                            pass that gives the block adjacency graph fewer colours\n"
    "                            (more blocks per IRBCD round) for at most 25 % more cut;\n"
    "                            cut: the preset's partition as it is (docs/partitioning.md)\n"
    "  --partition-time S        cap the partitioner's search at S seconds of wall time\n"
    "                            (default 0: no cap, the preset's own effort; with a cap the\n"
    "                            partition depends on the machine's speed)\n"
    "  --partition-file FILE     the block of every pose from FILE instead of a search (one\n"
    "                            block id per line, as tessera partition --out writes, or a\n"
    "                            JSON object with an \"assignment\" array); ids 0..agents-1\n"
    "  --init chordal|distributed|file   initial guess (default chordal; file = VERTEX poses)\n"
    "  --robots R                robots of --init distributed: R contiguous id ranges (default N)\n"
    "  --grad-tol T              stop at ||grad f|| <= T, full cost (default 0.01)\n"
    "  --max-rounds K            round cap (default 10000)\n"
    "  --rel-tol T               stop when a round decreases f by < T f (default 0: off)\n"
    "  --select greedy|greedy_newton|uniform|round_robin   block selection (default greedy)\n"
    "  --parallel                update a whole colour class of blocks (an independent set)\n"
    "                            per round (the default)\n"
    "  --sequential              one block per round (RBCD's and the baseline's rounds)\n"
    "  --seed S                  shared seed (uniform selection, partitioner), >= 0 (default 1)\n"
    "  --rank R                  relaxation rank (default 5)\n"
    "  --tr-steps K              trust-region steps per block update, every algorithm\n"
    "                            (default 1; IRBCD: see --irbcd-tr-steps)\n"
    "  --tr-grad-reduction F     with --tr-steps K > 1: stop a block update early once its\n"
    "                            block gradient fell to F times its start value (default 0:\n"
    "                            always K steps)\n"
    "  --irbcd-tr-steps K, --irbcd-grad-reduction F   the same for IRBCD only (RBCD and\n"
    "                            RBCD++ keep --tr-steps, --tr-grad-reduction) (defaults 2,\n"
    "                            0.2; K = 0, F < 0: take --tr-steps, --tr-grad-reduction)\n"
    "  --tcg-iters K             truncated-CG iterations per trust-region step (default 50)\n"
    "  --tcg-kappa K             tCG's relative residual target per step, in (0, 1) (default 0.1)\n"
    "  --block-precon tangent|euclidean   block updates' tCG preconditioner: the tangent-\n"
    "                            coordinate factor J A^-1 J^T at rank-d points (default), or\n"
    "                            the Q_BB factor (docs/irbcd.md section 5)\n"
    "  --tangent-refresh K       refactor the tangent factor at the current point every K\n"
    "                            updates of an agent (default 0: once, at its first update)\n"
    "  --tangent-radius S        first trust-region radius of a tangent-preconditioned update,\n"
    "                            in units of its preconditioned gradient norm (default 3)\n"
    "  --tangent-dots split|sequential   the tangent factor's backward dot products as four\n"
    "                            partial sums (default) or CHOLMOD's sequential sums (its bits)\n"
    "  --restart-c C             restart constant c1 of RBCD++/IRBCD (< 0: never restart;\n"
    "                            default 0)\n"
    "  --sigma S                 IRBCD sigma (default 1e-4; the paper: 1e-3)\n"
    "  --sigma-adapt, --sigma-fixed   IRBCD: adapt sigma at restarts / when gamma saturates\n"
    "                            (docs/irbcd.md section 3), or keep it fixed (default)\n"
    "  --sigma-shrink F, --sigma-saturation S, --sigma-theta T, --sigma-min A, --sigma-max B\n"
    "                            adaptive sigma's constants (IrbcdOptions); defaults and\n"
    "                            ranges: F 0.25 in (0, 1], S 0.9 in (0, 1], T 0.5 > 0,\n"
    "                            A 1e-8 >= 0, B 1e-4 >= A\n"
    "  --irbcd-a0 A              IRBCD: initial a (default: the a whose first gamma is 1;\n"
    "                            <= 0: 1/n, the paper's)\n"
    "  --irbcd-class-score norm|max   IRBCD, parallel greedy rounds: the colour class with the\n"
    "                            largest class gradient norm, or the class of the largest\n"
    "                            block gradient (RBCD++'s rule) (default: max)\n"
    "  --coarse on|off           two-level rounds: each scheduled round also moves every block\n"
    "                            rigidly by the solution of a small coarse problem over the cut\n"
    "                            (docs/irbcd.md, \"Coarse correction\") (default off)\n"
    "  --coarse-every K          with --coarse on: correct every K-th round (default 1)\n"
    "  --coarse-min-gain F       apply a correction only when it lowers f by >= F times the\n"
    "                            last round's decrease (default 0)\n"
    "  --coarse-space blocks|smoothed   with --coarse on: one rigid motion per block, or a few\n"
    "                            rigid pieces per block blended smoothly across their borders\n"
    "                            (smoothed aggregation; default blocks)\n"
    "  --coarse-aggregates K     smoothed: pieces grown per block (default 4)\n"
    "  --coarse-smoothing S      smoothed: smoothing steps of the blend, 0..8 (default 1)\n"
    "  --irbcd-keep-ab           IRBCD: keep a, b running after a restart (the default)\n"
    "  --unselected take|keep    IRBCD: unselected blocks take P^k or keep Y^k (default take)\n"
    "  --irbcd-n units|variables IRBCD: n = selectable blocks (default) or scalar variables\n"
    "  --reference               also run the centralized solver for f* and report rel_gap\n"
    "  --reference-cost F        f* given: report rel_gap = (cost - F) / F\n"
    "  --trace FILE              CSV per round: round,cost,grad_norm,selected,restart,bytes\n"
    "  --certify                 after the solve, certify global optimality distributedly\n"
    "                            (lambda_min of S by LOBPCG over neighbour exchanges) and climb\n"
    "                            the staircase on a saddle (off by default; see\n"
    "                            docs/distributed-certification.md). certified = the interface\n"
    "                            test proved a lower bound f_lb on the optimum (weak duality)\n"
    "                            with f(X) - f_lb <= 1e-4 max(1, |f(X)|) (JSON\n"
    "                            certificate_method exact, dual_lower_bound,\n"
    "                            suboptimality_bound = cost - f_lb), or, without that test,\n"
    "                            LOBPCG's lambda_min >= -eta at |grad f| <= 1e-4 max(1, |f|)\n"
    "                            (certificate_method lobpcg, no bound)\n"
    "  --max-rank R              staircase ceiling with --certify (default 10)\n"
    "  --certify-grad-tol T      with --certify, each rank is solved to --grad-tol and\n"
    "                            certified; if that certificate does not hold, the rank is\n"
    "                            refined and certified again before a saddle escape: by\n"
    "                            the Newton refinement (--refine auto|newton), else by\n"
    "                            rounds to this tolerance (default 1e-4; 0 = escape\n"
    "                            without refining)\n"
    "  --certify-iters K         certificate iteration cap (default 1000)\n"
    "  --certify-residual T      certificate stops at Ritz residual <= T max(1, max diag Q)\n"
    "                            (default 1e-6)\n"
    "  --certify-precon block-jacobi|none   certificate preconditioner (default block-jacobi)\n"
    "  --certify-interface C     exact test of S + D > 0 on the blocks' interfaces before\n"
    "                            LOBPCG when they have at most C coordinates (default 800;\n"
    "                            0 = LOBPCG only: an estimate, certified only where\n"
    "                            |grad f| <= 1e-4 max(1, |f|), no bound proved;\n"
    "                            docs/distributed-certification.md)\n"
    "  --certify-interface-sides one|both   the interface test keeps one endpoint of each cut\n"
    "                            measurement and eliminates the other in its block, or both\n"
    "                            (default one: about half the coordinates)\n"
    "  --refine newton|auto|none   after the rounds reach --grad-tol, trust-region Newton\n"
    "                            steps on the whole problem, CG over neighbour exchanges and\n"
    "                            all-agent sums (docs/newton-refine.md) (default auto); auto:\n"
    "                            where the team's interface fits the refinement's exact\n"
    "                            interface solves (<= 1000 tangent coordinates) the rounds\n"
    "                            stop at gradient 30 and the refinement always runs; elsewhere\n"
    "                            only where the rounds' last cost decreases say they stopped\n"
    "                            more than 1e-7 of f above their limit\n"
    "  --refine-grad-tol T       the refinement stops at ||grad f|| <= T (default 1e-6) or\n"
    "                            after a step that lowered f by < F f, --refine-rel-tol F\n"
    "                            (default 1e-7)\n"
    "  --refine-cg-iters K       its CG iteration cap, all steps (default 10000)\n"
    "  --refine-coarse smoothed|blocks|none   the coarse correction of its CG's block-Jacobi\n"
    "                            preconditioner: rigid motions of K pieces per block blended\n"
    "                            smoothly, one rigid motion per block, or none (default\n"
    "                            none)\n"
    "  --refine-coarse-aggregates K   pieces per block of the smoothed space (default 8)\n"
    "  --refine-coarse-form balancing|additive   how the coarse correction joins block\n"
    "                            Jacobi (default balancing)\n"
    "  --refine-interface C      its CG's preconditioner solves with the Hessian exactly\n"
    "                            through the blocks' interfaces where the team's interface has\n"
    "                            at most C tangent coordinates; 0 = block Jacobi always\n"
    "                            (default 1000; with --refine auto it also sets where the\n"
    "                            rounds hand over at gradient 30)\n"
    "  --refine-translation-interface P   a trial point's translations are solved exactly\n"
    "                            through the blocks' interfaces (one all-agent sum) where the\n"
    "                            team's interface has at most P poses; 0 = block-Jacobi CG\n"
    "                            always (default 2000)\n"
    "  --refine-gauge project|ground   with the interface solves, its CG works on the\n"
    "                            tangent vectors orthogonal to the global rigid motions\n"
    "                            (project) or holds the grounded pose fixed (ground) (default\n"
    "                            ground)\n"
    "  --refine-sigma one|every|solve  with the interface solves, agent 0 factors the\n"
    "                            interface matrix from shares sent with an accepted trial's\n"
    "                            sums and sends its factor (one), every agent factors it at\n"
    "                            every point (every), or agent 0 alone factors it and sends\n"
    "                            each agent its part of every solve (solve: one more message\n"
    "                            step a CG iteration); the same iterates (default solve)\n";

namespace {

void write_trace(const std::string& path, const DistributedResult& r) {
  std::ofstream out(path);
  if (!out) throw InputError(path, 0, "cannot open for writing");
  out << "round,cost,grad_norm,selected,restart,bytes,elapsed_s\n";
  char buf[256];
  for (const auto& row : r.trace) {
    std::string sel;
    for (std::size_t k = 0; k < row.selected.size(); ++k)
      sel += (k ? ";" : "") + std::to_string(row.selected[k]);
    std::snprintf(buf, sizeof buf, "%d,%.17g,%.17g,%s,%d,%llu,%.6f\n", row.round, row.cost,
                  row.grad_norm, sel.c_str(), row.restart ? 1 : 0,
                  static_cast<unsigned long long>(row.bytes), row.elapsed_s);
    out << buf;
  }
  if (!out) throw InputError(path, 0, "write failed");
}

// --partition-file: the given blocks with the figures a search reports (no search time).
PartitionResult given_partition(const PoseGraph& graph, const std::string& path, int parts) {
  PartitionResult part;
  part.assignment = read_partition(path, graph.num_poses);
  std::vector<bool> used(static_cast<std::size_t>(parts), false);
  for (int b : part.assignment) {
    if (b >= parts)
      throw InputError(
          path, 0,
          "block " + std::to_string(b) + " is not below --agents " + std::to_string(parts));
    used[static_cast<std::size_t>(b)] = true;
  }
  for (int b = 0; b < parts; ++b)
    if (!used[static_cast<std::size_t>(b)])
      throw InputError(path, 0, "block " + std::to_string(b) + " holds no pose");
  const GraphStructure structure = graph_structure_from_pose_graph(graph);
  part.metrics = compute_partition_metrics(structure, part.assignment, parts);
  const BlockAdjacency adjacency = block_adjacency(structure, part.assignment, parts);
  part.adjacent_block_pairs = adjacency.adjacent_block_pairs;
  part.colours = adjacency.colours;
  return part;
}

}  // namespace

int solve_distributed_command(const Arguments& a, const std::string& graph_path,
                              const RobustOptions& robust,
                              std::chrono::steady_clock::time_point start) {
  DistributedOptions opt;
  opt.algorithm = parse_algorithm(a.get_or("algorithm", "irbcd"));
  opt.initialization = parse_init(a.get_or("init", "chordal"));
  opt.grad_norm_tol = a.get_double("grad-tol", opt.grad_norm_tol);
  opt.max_rounds = static_cast<int>(a.get_long("max-rounds", opt.max_rounds));
  opt.rel_cost_decrease_tol = a.get_double("rel-tol", opt.rel_cost_decrease_tol);
  opt.selection = parse_selection(a.get_or("select", selection_name(opt.selection)));
  if (a.has("parallel") && a.has("sequential"))
    throw InputError("options --parallel and --sequential exclude each other");
  if (a.has("parallel")) opt.parallel = true;
  if (a.has("sequential")) opt.parallel = false;
  opt.robots = static_cast<int>(a.get_long("robots", 0));
  const long seed = a.get_long("seed", 1);
  if (seed < 0) throw InputError("option --seed: must be >= 0");
  opt.seed = static_cast<std::uint64_t>(seed);
  opt.rank = static_cast<int>(a.get_long("rank", opt.rank));
  opt.block_update.trust_region_steps =
      static_cast<int>(a.get_long("tr-steps", opt.block_update.trust_region_steps));
  opt.block_update.grad_reduction =
      a.get_double("tr-grad-reduction", opt.block_update.grad_reduction);
  // --tr-steps / --tr-grad-reduction set every algorithm's update, IRBCD's included, unless
  // its own flag is given too.
  if (a.has("tr-steps")) opt.irbcd_trust_region_steps = 0;
  if (a.has("tr-grad-reduction")) opt.irbcd_grad_reduction = -1.0;
  opt.irbcd_trust_region_steps =
      static_cast<int>(a.get_long("irbcd-tr-steps", opt.irbcd_trust_region_steps));
  opt.irbcd_grad_reduction = a.get_double("irbcd-grad-reduction", opt.irbcd_grad_reduction);
  opt.block_update.max_inner_iterations =
      static_cast<int>(a.get_long("tcg-iters", opt.block_update.max_inner_iterations));
  {
    const std::string precon = a.get_or("block-precon", "tangent");
    if (precon != "tangent" && precon != "euclidean")
      throw InputError("option --block-precon: '" + precon + "' is not one of tangent, euclidean");
    opt.block_update.tangent_preconditioner = precon == "tangent";
  }
  opt.block_update.tangent_refresh_interval =
      static_cast<int>(a.get_long("tangent-refresh", opt.block_update.tangent_refresh_interval));
  opt.block_update.tangent_radius_scale =
      a.get_double("tangent-radius", opt.block_update.tangent_radius_scale);
  opt.block_update.tangent_split_dots = tangent_split_dots_of(a);
  opt.block_update.max_attempts =
      std::max(opt.block_update.max_attempts, opt.block_update.trust_region_steps);
  if (a.has("restart-c")) {
    opt.irbcd.restart_c = a.get_double("restart-c", 0);
    opt.rbcd_plus_plus.restart_c = opt.irbcd.restart_c;
  }
  if (a.has("coarse")) {
    const std::string c = a.get_or("coarse", "");
    if (c != "on" && c != "off")
      throw InputError("option --coarse: '" + c + "' is not one of on, off");
    opt.coarse.enabled = c == "on";
  }
  opt.coarse.every = static_cast<int>(a.get_long("coarse-every", opt.coarse.every));
  opt.coarse.min_gain = a.get_double("coarse-min-gain", opt.coarse.min_gain);
  if (a.has("coarse-space")) opt.coarse.space = parse_coarse_space(a.get_or("coarse-space", ""));
  opt.coarse.aggregates = static_cast<int>(a.get_long("coarse-aggregates", opt.coarse.aggregates));
  opt.coarse.smoothing_steps =
      static_cast<int>(a.get_long("coarse-smoothing", opt.coarse.smoothing_steps));
  opt.irbcd.sigma = a.get_double("sigma", opt.irbcd.sigma);
  if (a.has("irbcd-a0")) opt.irbcd.unit_first_gamma = false;
  opt.irbcd.a0 = a.get_double("irbcd-a0", opt.irbcd.a0);
  if (a.has("irbcd-class-score"))
    opt.irbcd.class_score = parse_class_score(a.get_or("irbcd-class-score", ""));
  if (a.has("irbcd-keep-ab")) opt.irbcd.reset_on_restart = false;
  if (a.has("sigma-adapt")) opt.irbcd.adaptive_sigma = true;
  if (a.has("sigma-fixed")) opt.irbcd.adaptive_sigma = false;
  opt.irbcd.sigma_shrink = a.get_double("sigma-shrink", opt.irbcd.sigma_shrink);
  opt.irbcd.sigma_saturation = a.get_double("sigma-saturation", opt.irbcd.sigma_saturation);
  opt.irbcd.sigma_restart_theta = a.get_double("sigma-theta", opt.irbcd.sigma_restart_theta);
  opt.irbcd.sigma_min = a.get_double("sigma-min", opt.irbcd.sigma_min);
  opt.irbcd.sigma_max = a.get_double("sigma-max", opt.irbcd.sigma_max);
  const std::string unselected = a.get_or("unselected", "take");
  if (unselected != "take" && unselected != "keep")
    throw InputError("option --unselected: '" + unselected + "' is not one of take, keep");
  opt.irbcd.unselected_take_extrapolation = unselected == "take";
  opt.irbcd.dimension = parse_dimension(a.get_or("irbcd-n", "units"));
  opt.certify = a.has("certify");
  opt.staircase.max_rank = static_cast<int>(a.get_long("max-rank", opt.staircase.max_rank));
  opt.staircase.grad_norm_tol = a.get_double("certify-grad-tol", opt.staircase.grad_norm_tol);
  opt.staircase.certificate.residual_tolerance =
      a.get_double("certify-residual", opt.staircase.certificate.residual_tolerance);
  {
    const std::string precon = a.get_or("certify-precon", "block-jacobi");
    if (precon != "block-jacobi" && precon != "none")
      throw InputError("option --certify-precon: '" + precon +
                       "' is not one of block-jacobi, none");
    opt.staircase.certificate.preconditioner = precon == "none"
                                                   ? CertificatePreconditioner::kNone
                                                   : CertificatePreconditioner::kBlockJacobi;
  }
  opt.staircase.certificate.max_iterations =
      static_cast<int>(a.get_long("certify-iters", kCommandCertificateIterations));
  opt.staircase.certificate.interface_max_coordinates = static_cast<int>(
      a.get_long("certify-interface", opt.staircase.certificate.interface_max_coordinates));
  {
    const std::string sides = a.get_or("certify-interface-sides", "one");
    if (sides != "one" && sides != "both")
      throw InputError("option --certify-interface-sides: '" + sides + "' is not one of one, both");
    opt.staircase.certificate.interface_one_side = sides == "one";
  }
  {
    set_refine_mode(opt.refine, a.get_or("refine", "auto"));
    opt.refine.grad_norm_tol = a.get_double("refine-grad-tol", opt.refine.grad_norm_tol);
    opt.refine.relative_decrease_tol =
        a.get_double("refine-rel-tol", opt.refine.relative_decrease_tol);
    opt.refine.max_cg_iterations =
        static_cast<int>(a.get_long("refine-cg-iters", opt.refine.max_cg_iterations));
    opt.refine.coarse = coarse_from_flag("--refine-coarse", a.get_or("refine-coarse", "none"));
    const std::string form = a.get_or("refine-coarse-form", "balancing");
    if (form != "balancing" && form != "additive")
      throw InputError("option --refine-coarse-form: '" + form +
                       "' is not one of balancing, additive");
    opt.refine.coarse_balancing = form == "balancing";
    opt.refine.coarse_aggregates =
        static_cast<int>(a.get_long("refine-coarse-aggregates", opt.refine.coarse_aggregates));
    const long interface = a.get_long("refine-interface", opt.refine.interface_max_coordinates);
    if (interface < 0 || interface > 1000000)
      throw InputError("option --refine-interface: must be in 0..1000000");
    opt.refine.interface_max_coordinates = static_cast<int>(interface);
    const long translation =
        a.get_long("refine-translation-interface", opt.refine.translation_interface_max_poses);
    if (translation < 0 || translation > 1000000)
      throw InputError("option --refine-translation-interface: must be in 0..1000000");
    opt.refine.translation_interface_max_poses = static_cast<int>(translation);
    const std::string gauge =
        a.get_or("refine-gauge", opt.refine.project_gauge ? "project" : "ground");
    if (gauge != "project" && gauge != "ground")
      throw InputError("option --refine-gauge: '" + gauge + "' is not one of project, ground");
    opt.refine.project_gauge = gauge == "project";
    set_sigma_mode(opt.refine, a.get_or("refine-sigma", sigma_mode(opt.refine)));
  }
  const long agents = a.get_long("agents", 5);
  if (agents < 1 || agents > 64) throw InputError("option --agents: must be in 1..64");
  if (a.has("reference") && a.has("reference-cost"))
    throw InputError("options --reference and --reference-cost exclude each other");
  opt.validate();

  G2oReadOptions read;
  read.normalize_quaternions = !a.has("raw-quaternions");
  const LoadedGraph input = load_graph(a, graph_path, read);
  const PoseGraph& graph = input.graph;
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (static_cast<std::size_t>(agents) > graph.num_poses)
    throw InputError("option --agents: more agents than the graph's " +
                     std::to_string(graph.num_poses) + " poses");
  PartitionOptions popt;
  popt.parts = static_cast<int>(agents);
  popt.preset = parse_preset_for(a.get_or("partition", "auto"), graph.num_poses);
  popt.seed = opt.seed;
  popt.objective = parse_objective(a.get_or("partition-objective", "rounds"));
  popt.time_limit_s = a.get_double("partition-time", 0.0);
  if (!(popt.time_limit_s >= 0.0))
    throw InputError("option --partition-time: must be >= 0 seconds (0 = no cap)");
  popt.validate();
  const std::optional<std::string> partition_file = a.get("partition-file");
  if (partition_file && a.has("partition"))
    throw InputError("options --partition and --partition-file exclude each other");
  PartitionResult part = partition_file
                             ? given_partition(graph, *partition_file, popt.parts)
                             : partition_graph(graph_structure_from_pose_graph(graph), popt);
  if (popt.preset == PartitionPreset::kSequential)  // a multi-robot file: each robot its poses
    if (auto by_robot = robot_partition(input.keys, graph.num_poses, popt.parts)) {
      part.assignment = std::move(*by_robot);
      part.metrics = compute_partition_metrics(graph_structure_from_pose_graph(graph),
                                               part.assignment, popt.parts);
      const BlockAdjacency adjacency =
          block_adjacency(graph_structure_from_pose_graph(graph), part.assignment, popt.parts);
      part.adjacent_block_pairs = adjacency.adjacent_block_pairs;
      part.colours = adjacency.colours;
    }
  GncDistributedResult gnc;
  if (robust.kind != RobustKind::kNone) {
    // Like the centralized robust solve: the known inliers' start unless --init is given.
    GncDistributedOptions options;
    options.solver = opt;
    options.robust = robust;
    options.known_inlier_flags = input.known_inlier;
    options.known_inlier_start = !a.has("init");
    options.cluster_probes =
        static_cast<int>(a.get_long("gnc-cluster-probes", options.cluster_probes));
    if (options.cluster_probes < 0)
      throw InputError("option --gnc-cluster-probes: GncDistributedOptions.cluster_probes = " +
                       std::to_string(options.cluster_probes) + ": must be >= 0 (0 = none)");
    gnc = solve_gnc_distributed(graph, part.assignment, options);
  } else {
    gnc.final_solve = solve_distributed(graph, part.assignment, opt);
  }
  const DistributedResult& r = gnc.final_solve;

  std::optional<double> fstar;
  if (a.has("reference")) fstar = solve_centralized(graph).cost;
  if (a.has("reference-cost")) fstar = a.get_double("reference-cost", 0);
  std::optional<double> rel_gap;
  if (fstar) rel_gap = (r.cost - *fstar) / std::abs(*fstar);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf(
      "%s: %zu poses, %zu edges, d = %d; %s, %ld agents, %s partition (cut %lld, %d colours)\n",
      graph_path.c_str(), graph.num_poses, graph.num_measurements(), graph.d,
      algorithm_name(opt.algorithm), agents, partition_file ? "file" : preset_name(popt.preset),
      static_cast<long long>(part.metrics.cut_edges), part.colours);
  std::printf("  %d rounds (%d restarts), stop: %s, |grad f| = %.4g, relaxation f = %.10g\n",
              r.rounds, r.restarts, r.stop_reason.c_str(), r.grad_norm, r.relaxation_cost);
  std::printf("  rounded cost %.10g", r.cost);
  if (rel_gap) std::printf(", f* %.10g, rel gap %.3g", *fstar, *rel_gap);
  std::printf(
      "\n  %.3f MB exchanged, %.2f ms per round (%.2f CPU, %.2f on the slowest agent), solve %.3f "
      "s, wall %.3f s\n",
      r.bytes_exchanged / 1e6, r.rounds > 0 ? 1e3 * r.solve_s / r.rounds : 0.0,
      r.rounds > 0 ? 1e3 * r.solve_cpu_s / r.rounds : 0.0,
      r.rounds > 0 ? 1e3 * r.critical_path_cpu_s / r.rounds : 0.0, r.solve_s, wall_s);
  std::printf("  load %.3f s, partition %.3f s, set-up %.3f s, rounds %.3f s, rounding %.3f s\n",
              load_s, part.time_ms / 1e3, r.init_s, r.solve_s, r.rounding_s);
  if (r.certified) {
    std::printf(
        "  %s: lambda_min(S) = %.4g (eta %.3g, residual %.3g), %d certificate rounds "
        "(%.3f MB), %d escape rounds (%.3f MB), final rank %d\n",
        *r.certified ? "certified optimal" : "NOT certified", r.min_eigenvalue,
        r.certificate_tolerance, r.certificate_residual, r.certificate_rounds,
        r.certificate_bytes / 1e6, r.escape_rounds, r.escape_bytes / 1e6, r.final_rank);
    std::printf("%s", certificate_bound_line(r.certificate_bound, r.cost).c_str());
  }
  for (const NewtonRefineResult& n : r.refines)
    std::printf(
        "  newton refine: %d steps (%d accepted), %d CG iterations, %d translation CG "
        "iterations, %d exact translation solves (%d interface poses), %d exchanges, %d "
        "all-agent sums, %d coarse unknowns, interface %d coordinates (%d factorizations, %d "
        "fallbacks), |grad f| %.3g -> %.3g, f %.10g -> %.10g, stop: %s\n",
        n.steps, n.accepted_steps, n.cg_iterations, n.translation_iterations, n.translation_solves,
        n.translation_interface_poses, n.exchanges, n.reductions, n.coarse_unknowns,
        n.interface_coordinates, n.interface_factorizations, n.interface_fallbacks,
        n.initial_grad_norm, n.grad_norm, n.initial_cost, n.cost, n.stop_reason.c_str());
  for (const NewtonRefineResult& n : r.refines)
    std::printf(
        "  newton refine, agent 0: %.3f s wall, %.3f CPU-s: set-up %.3f, factors %.3f, Sigma "
        "%.3f, CG %.3f, trial points %.3f, translations %.3f; Sigma factored %d, taken from "
        "agent 0 %d; trial block factors unused %d\n",
        n.times.wall_s, n.times.cpu_s, n.times.setup_s, n.times.factor_s, n.times.sigma_s,
        n.times.cg_s, n.times.trial_s, n.times.translations_s, n.sigma_factorizations,
        n.sigma_imports, n.pending_factors_unused);
  for (const NewtonRefineResult& n : r.refines)
    for (std::size_t k = 0; k < n.trace.size(); ++k) {
      const NewtonRefineStep& t = n.trace[k];
      std::printf(
          "    step %zu: %d CG (%s), %d translation CG, radius %.3g, step %.3g, predicted %.3g, "
          "actual %.3g, %s, f %.12g, |grad f| %.3g\n",
          k + 1, t.cg_iterations, t.cg_stop.c_str(), t.translation_iterations, t.radius,
          t.step_norm, t.predicted, t.actual, t.accepted ? "accepted" : "rejected", t.cost,
          t.grad_norm);
    }
  if (robust.kind != RobustKind::kNone)
    std::printf(
        "  robust %s: %d outer steps, %zu of %zu measurements rejected, %d rounds and %.3f MB "
        "in all; cost over the kept ones\n",
        robust_kind_name(robust.kind), gnc.outer_iterations, gnc.rejected.size(),
        graph.num_measurements(), gnc.total_rounds, gnc.total_bytes / 1e6);
  if (auto p = a.get("rejected")) write_rejected(*p, gnc.rejected);
  write_solution_files(a, graph, input.keys, r.poses);
  if (auto p = a.get("trace")) write_trace(*p, r);
  if (auto p = a.get("json")) {
    SolveSummary summary;
    summary.algorithm = algorithm_name(opt.algorithm);
    summary.rank = opt.rank;
    summary.iterations = r.rounds;
    summary.grad_norm = r.grad_norm;
    summary.cost = r.cost;
    summary.relaxation_cost = r.relaxation_cost;
    summary.certified = r.certified;
    JsonObject j = solve_json(graph_path, graph, summary);
    j.add("wall_s", wall_s)
        .add("agents", static_cast<int>(agents))
        .add("partition", partition_file ? "file" : preset_name(popt.preset))
        .add("cut_edges", static_cast<long long>(part.metrics.cut_edges))
        .add("partition_objective", objective_name(popt.objective))
        .add("colours", part.colours)
        .add("adjacent_block_pairs", part.adjacent_block_pairs)
        .add("init", init_name(opt.initialization))
        .add("selection", selection_name(opt.selection))
        .add("parallel", opt.parallel)
        .add("rounds", r.rounds)
        .add("restarts", r.restarts)
        .add("stop_reason", r.stop_reason)
        .add("bytes_exchanged", static_cast<long long>(r.bytes_exchanged))
        .add("messages", static_cast<long long>(r.messages))
        .add("load_s", load_s)
        .add("partition_ms", part.time_ms)
        .add("partition_cpu_ms", part.cpu_ms)
        .add("init_s", r.init_s)
        .add("solve_s", r.solve_s)
        .add("rounding_s", r.rounding_s)
        .add("ms_per_round", r.rounds > 0 ? 1e3 * r.solve_s / r.rounds : 0.0)
        .add("solve_cpu_s", r.solve_cpu_s)
        .add("cpu_ms_per_round", r.rounds > 0 ? 1e3 * r.solve_cpu_s / r.rounds : 0.0)
        .add("critical_path_cpu_s", r.critical_path_cpu_s)
        .add("rel_gap", rel_gap)
        .add("final_rank", r.final_rank)
        .add("block_updates", r.block_updates)
        .add("tcg_iterations", r.tcg_iterations)
        .add("tcg_per_update", r.block_updates > 0 ? static_cast<double>(r.tcg_iterations) /
                                                         static_cast<double>(r.block_updates)
                                                   : 0.0)
        .add("tangent_updates", r.tangent_updates)
        .add("tangent_factorizations", r.tangent_factorizations);
    if (r.certified) {
      j.add("min_eigenvalue", r.min_eigenvalue)
          .add("certificate_tolerance", r.certificate_tolerance)
          .add("certificate_residual", r.certificate_residual)
          .add("certificate_rounds", r.certificate_rounds)
          .add("certificate_bytes", static_cast<long long>(r.certificate_bytes))
          .add("refine_rounds", r.refine_rounds)
          .add("escape_rounds", r.escape_rounds)
          .add("escape_bytes", static_cast<long long>(r.escape_bytes))
          .add("staircase_levels", static_cast<int>(r.certificates.size()));
      add_certificate_bound(j, r.certificate_bound, r.cost);
    } else {
      j.add_null("min_eigenvalue").add_null("certificate_rounds");
    }
    // --refine newton, or the robust final solve's refinement (--gnc-final-refine).
    if (opt.refine.enabled || !r.refines.empty()) {
      int steps = 0, accepted = 0, cg = 0, translation_cg = 0, exchanges = 0, reductions = 0;
      int interface = 0, interface_factorizations = 0, translation_solves = 0;
      int translation_interface = 0;
      for (const NewtonRefineResult& n : r.refines) {
        interface = std::max(interface, n.interface_coordinates);
        interface_factorizations += n.interface_factorizations;
        translation_solves += n.translation_solves;
        translation_interface = std::max(translation_interface, n.translation_interface_poses);
        steps += n.steps;
        accepted += n.accepted_steps;
        cg += n.cg_iterations;
        translation_cg += n.translation_iterations;
        exchanges += n.exchanges;
        reductions += n.reductions;
      }
      j.add("refine_steps", steps)
          .add("refine_accepted_steps", accepted)
          .add("refine_cg_iterations", cg)
          .add("refine_translation_iterations", translation_cg)
          .add("refine_translation_solves", translation_solves)
          .add("refine_translation_interface_poses", translation_interface)
          .add("refine_exchanges", exchanges)
          .add("refine_reductions", reductions)
          .add("refine_interface_coordinates", interface)
          .add("refine_interface_factorizations", interface_factorizations);
    }
    if (fstar) j.add("f_star", *fstar);
    if (robust.kind != RobustKind::kNone) {
      add_distributed_robust_fields(j, robust, gnc, gnc.total_rounds, graph.num_measurements(),
                                    gnc.final_refine_message_steps, gnc.final_solve_stages);
      j.add("total_bytes", static_cast<long long>(gnc.total_bytes))
          .add("longest_message_chain", static_cast<long long>(gnc.longest_chain));
    } else {
      // Without GNC's exchanges: the plain run's count (DistributedResult's message_steps).
      j.add("solve_stages", r.solve_stages)
          .add("message_steps_total", message_steps(r))
          .add("longest_message_chain", static_cast<long long>(r.longest_chain));
    }
    write_output(*p, j.str());
  }
  return 0;
}

}  // namespace tessera::cli
