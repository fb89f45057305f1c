// Solve a g2o pose graph with N agents in this process: partition it into N blocks, run the
// distributed solver (IRBCD by default) on them, report.
//   solve_distributed GRAPH.g2o [N]

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: solve_distributed GRAPH.g2o [AGENTS]\n");
    return 2;
  }
  try {
    const tessera::PoseGraph graph = tessera::read_g2o(argv[1]);
    tessera::PartitionOptions partition;
    partition.parts = argc == 3 ? std::atoi(argv[2]) : 4;
    const tessera::PartitionResult blocks =
        tessera::partition_graph(tessera::graph_structure_from_pose_graph(graph), partition);
    tessera::DistributedOptions options;  // IRBCD, chordal start, gradient norm 0.01
    const tessera::DistributedResult result =
        tessera::solve_distributed(graph, blocks.assignment, options);
    std::printf("%s", result.full_report().c_str());
    return 0;
  } catch (const tessera::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
