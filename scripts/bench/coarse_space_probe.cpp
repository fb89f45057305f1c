// How much of f(X_k) - f* can one coarse correction remove, per coarse space? X_k is IRBCD's
// iterate after k rounds (one-level, in process); f* the optimum (pass it, e.g. a long run's
// f). For the block space (one rigid motion per block) and the smoothed space over a grid of
// pieces per block and smoothing steps, it solves the coarse problem at X_k, applies it and
// prints the real decrease of f as a share of f(X_k) - f*. Not part of the product.
//
//   g++ -O2 -std=c++17 -Icore/include -isystem /usr/include/eigen3
//       scripts/bench/coarse_space_probe.cpp build/lib/libtessera_core.a -lcholmod
//       -lsuitesparseconfig -lpthread -o /tmp/coarse_space_probe   (one line)
//   tessera generate --kind grid3d --poses 8000 --robots 5 --seed 1 --out grid.g2o
//   tessera partition grid.g2o --parts 49 --preset eco --objective rounds --out part.txt
//   /tmp/coarse_space_probe grid.g2o part.txt F_STAR 10 40 80
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/problem/block_problem.hpp>
#include <vector>

using namespace tessera;

namespace {

// f at a lifted iterate of the whole graph.
double f_of(const PoseGraph& g, const Eigen::MatrixXd& X) {
  return BlockProblem::whole_graph(g.d, g.num_poses, g.measurements).cost(X);
}

Eigen::MatrixXd columns(const Eigen::MatrixXd& X, int d, const std::vector<std::size_t>& ids) {
  Eigen::MatrixXd out(X.rows(), (d + 1) * static_cast<Eigen::Index>(ids.size()));
  for (std::size_t k = 0; k < ids.size(); ++k)
    out.middleCols((d + 1) * static_cast<Eigen::Index>(k), d + 1) =
        X.middleCols((d + 1) * static_cast<Eigen::Index>(ids[k]), d + 1);
  return out;
}

std::vector<const std::vector<double>*> pointers(const std::vector<std::vector<double>>& t) {
  std::vector<const std::vector<double>*> p;
  for (const auto& v : t) p.push_back(&v);
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s GRAPH PARTITION F_STAR ROUNDS...\n", argv[0]);
    return 2;
  }
  const PoseGraph g = read_g2o(argv[1]);
  std::vector<int> part;
  {
    std::ifstream in(argv[2]);
    for (int b; in >> b;) part.push_back(b);
  }
  const double fstar = std::stod(argv[3]);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  std::vector<std::size_t> all(g.num_poses);
  std::iota(all.begin(), all.end(), std::size_t{0});
  for (int a = 4; a < argc; ++a) {
    DistributedOptions o;
    o.max_rounds = std::stoi(argv[a]);
    o.grad_norm_tol = 0;
    o.round_result = false;
    const Eigen::MatrixXd X = solve_distributed(g, part, o).X;
    const double f = f_of(g, X), gap = f - fstar;
    std::printf("N = %d, round %s: f - f* = %.6g\n", layout.num_blocks, argv[a], gap);
    CoarseOptions c;
    c.max_iterations = 30;
    {
      std::vector<std::vector<double>> terms;
      for (int b = 0; b < layout.num_blocks; ++b) {
        const BlockProblem p(g.d, layout.poses[static_cast<std::size_t>(b)], g.measurements);
        const CoarseTerms t(b, g.d, layout, p.owned(), p.neighbors(), g.measurements);
        terms.push_back(t.compute(columns(X, g.d, p.owned()), columns(X, g.d, p.neighbors())));
      }
      const CoarseResult r = solve_coarse(layout, o.rank, pointers(terms), c);
      Eigen::MatrixXd Xc = X;
      for (std::size_t i = 0; i < g.num_poses; ++i)
        apply_motion(r.motions[static_cast<std::size_t>(part[i])], g.d, Xc,
                     static_cast<Eigen::Index>(i), 1);
      std::printf("  blocks (one rigid motion each): %5.1f %%\n", 100 * (f - f_of(g, Xc)) / gap);
    }
    for (int k : {1, 4, 16})
      for (int steps : {0, 1, 2}) {
        c.aggregates = k;
        c.smoothing_steps = steps;
        const CoarseSpace s = make_coarse_space(g.num_poses, g.measurements, part, c);
        std::vector<std::vector<double>> terms;
        for (int b = 0; b < layout.num_blocks; ++b) {
          const BlockProblem p(g.d, layout.poses[static_cast<std::size_t>(b)], g.measurements);
          const SmoothedCoarseTerms t(s, b, g.d, p.owned(), p.neighbors(), g.measurements);
          terms.push_back(t.compute(columns(X, g.d, p.owned()), columns(X, g.d, p.neighbors())));
        }
        const CoarseResult r = solve_smoothed_coarse(s, o.rank, pointers(terms), c);
        Eigen::MatrixXd Xc = X;
        apply_blended_motions(s, r.motions, g.d, all, Xc);
        std::printf(
            "  %2d pieces per block (%4d), %d smoothing steps: model %5.1f %%, real %5.1f %%\n", k,
            s.num_aggregates, steps, 100 * (r.cost_before - r.cost_after) / gap,
            100 * (f - f_of(g, Xc)) / gap);
      }
  }
}
