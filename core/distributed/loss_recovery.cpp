#include <algorithm>
#include <string>
#include <tessera/distributed/loss_recovery.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

LossRecoveryResult continue_after_loss(const PoseGraph& graph,
                                       const std::vector<int>& old_assignment, int num_agents,
                                       const std::vector<int>& lost, const Eigen::MatrixXd& current,
                                       const Eigen::MatrixXd& replica,
                                       const DistributedOptions& options,
                                       const SurvivorRepartitionOptions& repartition) {
  if (current.rows() != replica.rows() || current.cols() != replica.cols())
    throw InputError("loss recovery: the replica's shape differs from the current iterate's");
  const Eigen::Index w = graph.d + 1;
  if (current.cols() != w * static_cast<Eigen::Index>(graph.num_poses))
    throw InputError("loss recovery: the iterate has " + std::to_string(current.cols()) +
                     " columns for " + std::to_string(graph.num_poses) + " poses");
  LossRecoveryResult res;
  res.repartition = repartition_for_survivors(graph_structure_from_pose_graph(graph),
                                              old_assignment, num_agents, lost, repartition);
  res.start = current;
  for (std::size_t v = 0; v < graph.num_poses; ++v)
    if (std::find(lost.begin(), lost.end(), old_assignment[v]) != lost.end())
      res.start.middleCols(w * static_cast<Eigen::Index>(v), w) =
          replica.middleCols(w * static_cast<Eigen::Index>(v), w);
  res.run = solve_distributed_from_lifted(graph, res.repartition.block, options, res.start);
  return res;
}

}  // namespace tessera
