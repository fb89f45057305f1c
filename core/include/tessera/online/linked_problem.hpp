#pragma once
// The part of a growing graph that can be solved now. A pose no measurement touches yet (a
// robot's first pose before its odometry arrives) has nothing to optimise and would leave its
// block's Q_BB singular, so a step solves the linked poses only, with the blocks that have
// some, numbered compactly in increasing block order (a block's agent keeps its protocol id
// when every block has linked poses). Shared by the in-process engine (online_engine.hpp) and
// the DDS agents (agent/online_agent.cpp), so both solve the same problem at a step.

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct LinkedProblem {
  PoseGraph graph;                   ///< Linked poses only, compact ids.
  std::vector<int> blocks;           ///< Compact block of each compact pose.
  std::vector<std::size_t> full_id;  ///< Stream id of each compact pose.
  std::vector<int> block_of;         ///< Original block of each compact block.
  Eigen::MatrixXd X0;                ///< The iterate's columns of the linked poses.
  bool whole = false;                ///< Every pose linked: ids and blocks are the original ones.

  /// Compact block of original block `b`, or -1 when it has no linked pose.
  int compact_block(int b) const;
  /// Writes the compact iterate `X` (same rank) back into the stream-id iterate `full`.
  void write_back(const Eigen::MatrixXd& X, Eigen::MatrixXd& full) const;
};

/// `owner`: block of each pose of `graph`; `X`: r x (d+1)n iterate in the graph's ids.
LinkedProblem make_linked_problem(const PoseGraph& graph, const std::vector<int>& owner,
                                  const Eigen::MatrixXd& X);

}  // namespace tessera
