// Solve a g2o pose graph centrally and certify the optimum: read, solve, report.
//   solve_centralized GRAPH.g2o

#include <cstdio>
#include <exception>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: solve_centralized GRAPH.g2o\n");
    return 2;
  }
  try {
    const tessera::PoseGraph graph = tessera::read_g2o(argv[1]);
    const tessera::CentralizedResult result = tessera::solve_centralized(graph);
    std::printf("%zu poses, %zu measurements\n%s", graph.num_poses, graph.num_measurements(),
                result.full_report().c_str());
    return result.certified.value_or(false) ? 0 : 1;
  } catch (const tessera::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
