// Not a test: the figures of scripts/bench/rounding_blocks.py. The distributed rounding's
// translation CG against the number of blocks, on a generated 3D grid split by the `fast`
// partition (as `tessera launch` splits large graphs), after a few rounds of the in-process
// solver (a warm start far from the optimum, as a run capped by --max-rounds leaves it).
// For every block count and preconditioner it prints one line
//   ROUNDING_BLOCKS poses blocks rounds cut coarse settled exact excess target
// with the CG iterations (all-agent steps) to the default stop (cost settled) and to the
// residual stop alone (1e-12 of b's), the rounded cost above the latter's, and the stop's
// target. Exit 1 when an agent of the harness failed, 2 on bad arguments.
//
// usage: rounding_blocks_bench [--poses P] [--blocks 16,25,64] [--rounds R] [--seed S]

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <vector>

#include "rounding_threads.hpp"

int main(int argc, char** argv) {
  using namespace tessera;
  using namespace tessera::agent;
  std::size_t poses = 100000;
  std::vector<int> blocks = {16, 25, 64};
  int rounds = 5;
  std::uint64_t seed = 1;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string a = argv[k], v = argv[k + 1];
    if (a == "--poses") {
      poses = std::stoul(v);
    } else if (a == "--rounds") {
      rounds = std::stoi(v);
    } else if (a == "--seed") {
      seed = std::stoull(v);
    } else if (a == "--blocks") {
      blocks.clear();
      std::stringstream ss(v);
      for (std::string t; std::getline(ss, t, ',');) blocks.push_back(std::stoi(t));
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (argc % 2 == 0) {
    std::fprintf(stderr,
                 "usage: rounding_blocks_bench [--poses P] [--blocks 16,25,64] "
                 "[--rounds R] [--seed S]\n");
    return 2;
  }
  for (int N : blocks) {
    GeneratorOptions g;
    g.kind = TrajectoryKind::kGrid3d;
    g.num_poses = poses;
    g.num_robots = static_cast<std::size_t>(N);
    g.seed = seed;
    RoundingCase c;
    c.graph = generate_pose_graph(g).graph;
    PartitionOptions po;
    po.parts = N;
    po.preset = PartitionPreset::kFast;
    po.seed = seed;
    const PartitionResult part = partition_graph(graph_structure_from_pose_graph(c.graph), po);
    c.assignment = part.assignment;
    DistributedOptions o;
    o.max_rounds = rounds;
    c.solved = solve_distributed(c.graph, c.assignment, o);
    for (bool coarse : {false, true}) {
      DistributedRoundingOptions settled;
      settled.interface_max_poses = 0;  // the CG's steps
      settled.coarse_correction = coarse;
      DistributedRoundingOptions exact = settled;
      exact.settle_tolerance = 0;
      const Rounded a = round_in_threads(c, settled, 600.0);
      const Rounded b = round_in_threads(c, exact, 600.0);
      for (const Rounded* r : {&a, &b})
        if (!r->errors.empty()) {
          std::fprintf(stderr, "%d blocks: %s\n", N, r->errors.front().c_str());
          return 1;
        }
      std::printf("ROUNDING_BLOCKS %zu %d %d %zu %d %u %u %.3e %.3e\n", c.graph.num_poses, N,
                  c.solved.rounds, part.metrics.cut_edges, coarse ? 1 : 0, a.iterations,
                  b.iterations, a.cost - b.cost,
                  settled.settle_tolerance * std::max(1.0, c.solved.relaxation_cost));
      std::fflush(stdout);
    }
  }
  return 0;
}
