#include <algorithm>
#include <tessera/online/linked_problem.hpp>
#include <tessera/problem/lifting.hpp>

namespace tessera {

int LinkedProblem::compact_block(int b) const {
  auto it = std::find(block_of.begin(), block_of.end(), b);
  return it == block_of.end() ? -1 : static_cast<int>(it - block_of.begin());
}

void LinkedProblem::write_back(const Eigen::MatrixXd& X, Eigen::MatrixXd& full) const {
  scatter_pose_columns(X, full_id, graph.d, full);
}

LinkedProblem make_linked_problem(const PoseGraph& graph, const std::vector<int>& owner,
                                  const Eigen::MatrixXd& X) {
  LinkedProblem p;
  std::vector<char> linked(graph.num_poses, 0);
  for (const Measurement& m : graph.measurements) linked[m.i] = linked[m.j] = 1;
  p.whole = std::all_of(linked.begin(), linked.end(), [](char c) { return c != 0; });
  p.graph.d = graph.d;
  p.graph.source = graph.source;
  std::vector<std::size_t> sub_id(graph.num_poses, 0);
  for (std::size_t k = 0; k < graph.num_poses; ++k)
    if (linked[k]) {
      sub_id[k] = p.full_id.size();
      p.full_id.push_back(k);
      p.block_of.push_back(owner[k]);
    }
  std::sort(p.block_of.begin(), p.block_of.end());
  p.block_of.erase(std::unique(p.block_of.begin(), p.block_of.end()), p.block_of.end());
  p.graph.num_poses = p.full_id.size();
  p.graph.measurements.reserve(graph.measurements.size());
  for (const Measurement& m : graph.measurements) {
    Measurement e = m;
    e.i = sub_id[m.i];
    e.j = sub_id[m.j];
    p.graph.measurements.push_back(std::move(e));
  }
  const Eigen::Index w = graph.d + 1;
  p.X0.resize(X.rows(), w * static_cast<Eigen::Index>(p.graph.num_poses));
  for (std::size_t s = 0; s < p.full_id.size(); ++s) {
    p.blocks.push_back(p.compact_block(owner[p.full_id[s]]));
    p.X0.middleCols(w * static_cast<Eigen::Index>(s), w) =
        X.middleCols(w * static_cast<Eigen::Index>(p.full_id[s]), w);
  }
  return p;
}

}  // namespace tessera
