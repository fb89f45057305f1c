#include "solve_output.hpp"

#include <cstdio>
#include <tessera/graph/input_frame.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/robot_trajectories.hpp>
#include <tessera/io/tum_writer.hpp>

#include "heap_pages_json.hpp"

namespace tessera::cli {

void write_poses(const std::string& path, const PoseGraph& graph, const std::vector<Pose>& poses,
                 const PoseKeys& keys) {
  const bool tum = path.size() >= 4 && path.compare(path.size() - 4, 4, ".tum") == 0;
  if (tum)
    write_tum(poses, keys, path);
  else
    write_g2o(graph, keys, poses, path);
}

const char* const kSolutionOutputHelp =
    "  --tum-dir DIR             write one TUM file per robot, DIR/robot_<name>.tum (the\n"
    "                            poses' stamps, else their index, as timestamps)\n";

void write_solution_files(const Arguments& a, const PoseGraph& graph, const PoseKeys& keys,
                          std::vector<Pose> poses) {
  move_to_input_frame(graph, keys, poses);
  if (auto p = a.get("out")) write_poses(*p, graph, poses, keys);
  if (auto p = a.get("tum")) write_tum(poses, keys, *p);
  if (auto dir = a.get("tum-dir")) {
    const auto files = write_robot_trajectories(graph, keys, poses, *dir);
    std::fprintf(stderr, "wrote %zu robot trajectories into %s\n", files.size(), dir->c_str());
  }
}

JsonObject solve_json(const std::string& graph_path, const PoseGraph& graph,
                      const SolveSummary& summary) {
  JsonObject j;
  j.add("algorithm", summary.algorithm)
      .add("graph", graph_path)
      .add("poses", graph.num_poses)
      .add("edges", graph.num_measurements())
      .add("d", graph.d)
      .add("rank", summary.rank)
      .add("iterations", summary.iterations)
      .add("grad_norm", summary.grad_norm)
      .add("cost", summary.cost)
      .add("relaxation_cost", summary.relaxation_cost)
      .add("certified", summary.certified);
  add_heap_pages(j);
  return j;
}

}  // namespace tessera::cli
