// Not a test: the figures of scripts/bench/rounding_iterations.py. On each shared paper graph,
// 5 contiguous blocks, the in-process solver to its default tolerance (0.01) and to 30 rounds,
// then the distributed rounding from zero to the residual stop (the exact solve) and with the
// defaults (warm start, cost stop); one line "ROUNDING graph rounds cold warm excess target"
// each. Exit 1 when an agent of the harness failed, 2 when ../shared holds none of the graphs.

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>

#include "rounding_threads.hpp"

int main() {
  using namespace tessera;
  using namespace tessera::agent;
  int found = 0;
  for (const char* name : {"intel", "CSAIL", "sphere2500", "torus3D", "parking-garage", "cubicle",
                           "manhattan3500", "city10000", "kitti_00"}) {
    const std::string path = std::string(TESSERA_SHARED_DIR) + "/datasets/" + name + ".g2o";
    if (!std::ifstream(path)) continue;
    ++found;
    for (int rounds : {30, 10000}) {
      RoundingCase c;
      c.graph = read_g2o(path);
      for (std::size_t i = 0; i < c.graph.num_poses; ++i)
        c.assignment.push_back(static_cast<int>(i * 5 / c.graph.num_poses));
      DistributedOptions o;
      o.max_rounds = rounds;
      c.solved = solve_distributed(c.graph, c.assignment, o);
      DistributedRoundingOptions exact;
      exact.warm_start = false;
      exact.settle_tolerance = 0;
      const Rounded cold = round_in_threads(c, exact);
      const DistributedRoundingOptions defaults;
      const Rounded warm = round_in_threads(c, defaults);
      for (const Rounded* r : {&cold, &warm})
        if (!r->errors.empty()) {
          std::fprintf(stderr, "%s: %s\n", name, r->errors.front().c_str());
          return 1;
        }
      std::printf("ROUNDING %s %d %u %u %.3e %.3e\n", name, c.solved.rounds, cold.iterations,
                  warm.iterations, warm.cost - cold.cost,
                  defaults.settle_tolerance * std::max(1.0, c.solved.relaxation_cost));
      std::fflush(stdout);
    }
  }
  if (found == 0) {
    std::fprintf(stderr, "no paper graph under %s/datasets (../shared missing?)\n",
                 TESSERA_SHARED_DIR);
    return 2;
  }
  return 0;
}
