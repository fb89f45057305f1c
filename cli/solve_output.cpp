#include "solve_output.hpp"

#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/tum_writer.hpp>

namespace tessera::cli {

void write_poses(const std::string& path, const PoseGraph& graph, const std::vector<Pose>& poses) {
  const bool tum = path.size() >= 4 && path.compare(path.size() - 4, 4, ".tum") == 0;
  if (tum)
    write_tum(poses, path);
  else
    write_g2o(graph, poses, path);
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
  return j;
}

}  // namespace tessera::cli
