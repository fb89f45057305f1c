// Not a test: what a new tangent factor of one online block costs, piece by piece (the fixed cost
// of a step's first Newton point, docs/online.md). The block is robot `--robot` of a g2o graph
// split into `--robots` contiguous id ranges (as `tessera generate` numbers them), holding its
// first `--poses` poses, with the measurements among the poses that exist when every robot has
// published that many (a late online step). The point is the file's VERTEX estimate, lifted at
// rank d. Prints the factor entries and flops other orderings of the block's pose-level pattern
// would give (ORDERING amd|metis|nesdis|colamd entries E flops F), a hash of the factored
// operator applied to a fixed tangent vector (APPLY_HASH: the same bits, or not, across builds)
// and one line:
//   TANGENT_FACTOR poses neighbours entries flops construct_ms factorize_ms
// usage: tangent_factor_bench GRAPH.g2o [--robots 10] [--robot 0] [--poses 3400] [--repeat 1]
// Under callgrind with --instr-atstart=no only the construction and factorization are
// instrumented.

#include <valgrind/callgrind.h>

#include <Eigen/CholmodSupport>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <vector>

#include "solvers/pose_level_analysis.hpp"

namespace {

// Factor entries and flops of the pose-level pattern under one of CHOLMOD's orderings, times
// the p x p blocks (as pose_level_fill_estimate does): what another ordering would give A.
void ordering_line(const tessera::SparseMatrix& lower, int p, int ordering, const char* name) {
  cholmod_common c;
  cholmod_start(&c);
  c.nmethods = 1;
  c.method[0].ordering = ordering;
  c.postorder = 1;
  c.supernodal = CHOLMOD_SIMPLICIAL;
  const tessera::SparseMatrix l = [&] {
    tessera::SparseMatrix c = lower;
    c.makeCompressed();
    return c;
  }();
  cholmod_sparse a = Eigen::viewAsCholmod(l.selfadjointView<Eigen::Lower>());
  cholmod_factor* f = cholmod_analyze(&a, &c);
  if (f) {
    const double m = static_cast<double>(lower.rows());
    std::printf("ORDERING %s entries %.4g flops %.4g\n", name,
                (c.lnz - m) * p * p + m * p * (p + 1) / 2.0, c.fl * p * p * p);
    cholmod_free_factor(&f, &c);
  } else {
    std::printf("ORDERING %s failed (status %d)\n", name, c.status);
  }
  cholmod_finish(&c);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: tangent_factor_bench GRAPH.g2o [--robots R] [--robot r] "
                 "[--poses k] [--repeat n]\n");
    return 2;
  }
  std::size_t robots = 10, robot = 0, poses = 3400;
  int repeat = 1;
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string flag = argv[a];
    const long v = std::strtol(argv[a + 1], nullptr, 10);
    if (flag == "--robots")
      robots = static_cast<std::size_t>(v);
    else if (flag == "--robot")
      robot = static_cast<std::size_t>(v);
    else if (flag == "--poses")
      poses = static_cast<std::size_t>(v);
    else if (flag == "--repeat")
      repeat = static_cast<int>(v);
    else {
      std::fprintf(stderr, "unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  using namespace tessera;
  const PoseGraph g = read_g2o(argv[1]);
  const int d = g.d;
  const std::size_t n = g.num_poses, per = n / robots;
  const auto arrived = [&](std::size_t i) { return i % per < poses; };
  std::vector<Measurement> ms;
  for (const Measurement& m : g.measurements)
    if (arrived(m.i) && arrived(m.j)) ms.push_back(m);
  std::vector<std::size_t> owned;
  for (std::size_t i = robot * per; i < robot * per + poses && i < n; ++i) owned.push_back(i);
  BlockProblem problem(d, owned, ms);
  const Eigen::MatrixXd all = lift_poses(g.initial, d);
  problem.set_neighbor_poses(gather_pose_columns(all, problem.neighbors(), d));
  const Eigen::MatrixXd X = gather_pose_columns(all, owned, d);
  {
    SparseMatrix Q = problem.data_matrix();
    Q.makeCompressed();
    const SparseMatrix lower = pose_level_pattern(Q, d + 1);
    const int p = d * (d + 1) / 2;
    ordering_line(lower, p, CHOLMOD_AMD, "amd");
    ordering_line(lower, p, CHOLMOD_METIS, "metis");
    ordering_line(lower, p, CHOLMOD_NESDIS, "nesdis");
    ordering_line(lower, p, CHOLMOD_COLAMD, "colamd");
  }
  double construct_ms = 0, factor_ms = 0;
  std::size_t entries = 0;
  double flops = 0;
  for (int r = 0; r < repeat; ++r) {
    CALLGRIND_START_INSTRUMENTATION;
    const auto t0 = std::chrono::steady_clock::now();
    TangentPreconditioner t(problem, 1e-9, 16'000'000, 1e7, true);
    const auto t1 = std::chrono::steady_clock::now();
    const bool ok = t.usable() && t.factorize(X);
    const auto t2 = std::chrono::steady_clock::now();
    CALLGRIND_STOP_INSTRUMENTATION;
    if (!ok) {
      std::fprintf(stderr, "factorization failed\n");
      return 1;
    }
    construct_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    factor_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
    entries = t.factor_entries();
    if (r == 0) {  // the operator's bits: J A^-1 J^T of a fixed tangent vector
      const LiftedManifold M = problem.manifold(d);
      Eigen::MatrixXd V(d, X.cols());
      for (Eigen::Index k = 0; k < V.size(); ++k) V(k) = std::sin(0.37 * static_cast<double>(k));
      const Eigen::MatrixXd Z = t.apply(M, X, M.tangent_project(X, V));
      std::uint64_t h = 1469598103934665603ull;
      for (Eigen::Index k = 0; k < Z.size(); ++k) {
        std::uint64_t b = 0;
        std::memcpy(&b, Z.data() + k, sizeof b);
        h = (h ^ b) * 1099511628211ull;
      }
      std::printf("APPLY_HASH %016llx %.17g\n", static_cast<unsigned long long>(h), Z.norm());
    }
    flops = t.factor_flops();
  }
  std::printf("TANGENT_FACTOR %zu %zu %zu %.4g %.2f %.2f\n", owned.size(), problem.num_neighbors(),
              entries, flops, construct_ms / repeat, factor_ms / repeat);
  return 0;
}
