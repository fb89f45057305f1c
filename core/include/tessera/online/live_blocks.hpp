#pragma once
// The agents' block problems of an online run, kept from step to step. A step brings a few new
// poses and measurements; building every block problem, its data matrices and its
// preconditioner factors again for them (what a solve from scratch does) made the set-up cost
// of a step grow with the whole graph. Here a block that got new data grows in place
// (AgentState::extend: the new measurements are appended; with `refactor_growth` > 0 its factor
// is kept and the new poses are appended to it until the block has grown by that fraction), a
// block with nothing new is kept as it is, and only a block that lost
// or gained poses through a re-partition (rebalance_blocks) is built again.
//
// The solved graph is the linked part of the stream's graph (linked_problem.hpp: a pose no
// measurement touches yet has nothing to optimise), its poses numbered in the order they became
// linked (so the numbering only ever grows and every kept state stays valid) and its blocks, as
// in linked_problem.hpp, in increasing order of the blocks that have linked poses. Every agent
// that builds it from the same stream graph and blocks gets the same numbering, however the
// data was grouped into syncs (the DDS agents hold only their own block's state).

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// Tangent preconditioner factorizations and their floating-point operations as CHOLMOD's
/// symbolic analysis predicts them (load-free).
struct TangentFactorTotals {
  long long factorizations = 0;
  double flops = 0.0;

  TangentFactorTotals& operator+=(const TangentFactorTotals& o) {
    factorizations += o.factorizations;
    flops += o.flops;
    return *this;
  }
  /// The factorizations done since `before` (a total taken earlier).
  TangentFactorTotals since(const TangentFactorTotals& before) const {
    return {factorizations - before.factorizations, flops - before.flops};
  }
};

/// What one LiveBlocks::sync did.
struct LiveSync {
  std::size_t new_poses = 0, new_measurements = 0;  ///< Linked poses / measurements added.
  int built = 0;     ///< Block states built from scratch (new blocks, blocks a move changed).
  int extended = 0;  ///< Block states grown in place.
  int kept = 0;      ///< Block states with nothing new.
};

class LiveBlocks {
 public:
  /// `d`: 2 or 3. `update`: the agents' block update options (their preconditioners).
  /// `refactor_growth` (>= 0): a block's tangent factor is kept while the block holds at most
  /// this fraction more poses than it was computed for (AgentState::extend). `only_block`: the
  /// original block whose state is kept (a DDS agent's own), or -1 for every block.
  LiveBlocks(int d, const BlockUpdateOptions& update, double refactor_growth, int only_block = -1);

  /// Brings the blocks up to `graph` (the stream's graph: it only ever grows, ids dense),
  /// `owner` (original block of every pose of `graph`) and `X` (r x (d+1)n iterate in graph
  /// ids): the measurements added since the last call enter, each held state is grown, kept
  /// or built again, and every held state starts from X (momentum restarted).
  LiveSync sync(const PoseGraph& graph, const std::vector<int>& owner, const Eigen::MatrixXd& X);

  /// The linked graph (compact ids) and its blocks' layout.
  const PoseGraph& graph() const { return graph_; }
  const BlockLayout& layout() const { return *layout_; }
  /// Held states by compact block (null for blocks that are not held).
  const std::vector<std::unique_ptr<AgentState>>& states() const { return states_; }
  /// Every state, for solve_distributed_with_states (only when every block is held).
  std::vector<AgentState*> all_states() const;
  /// Stream id of each compact pose; original block of each compact block.
  const std::vector<std::size_t>& full_id() const { return full_id_; }
  const std::vector<int>& block_of() const { return block_of_; }
  /// Compact block of original block `b`, or -1 when it has no linked pose yet.
  int compact_block(int b) const;
  /// Tangent factorizations done by every state this object has held (AgentState's
  /// tangent_factorizations_total and tangent_factor_flops_total, states built again or dropped
  /// included).
  TangentFactorTotals tangent_factor_totals() const;
  /// Block states built from scratch by every sync so far (LiveSync::built summed).
  long long built_total() const { return built_total_; }
  /// Writes the compact iterate `Xc` (rank = X's rows) into the stream-id iterate `X`.
  void write_back(const Eigen::MatrixXd& Xc, Eigen::MatrixXd& X) const;

 private:
  Eigen::MatrixXd columns(const Eigen::MatrixXd& X, const std::vector<std::size_t>& compact) const;

  /// Adds a state's factorization totals to the retired ones before it is dropped.
  void retire(const std::unique_ptr<AgentState>& state);

  int d_;
  TangentFactorTotals retired_;  // of the states dropped or built again
  long long built_total_ = 0;
  BlockUpdateOptions update_;
  double refactor_growth_;
  int only_block_;
  PoseGraph graph_;
  std::size_t seen_measurements_ = 0;  // measurements of the stream graph read so far
  std::vector<std::size_t> full_id_;
  std::vector<std::size_t> compact_of_;  // by stream id; kNone when not linked
  std::vector<int> owner_;               // original block of each compact pose
  std::vector<int> block_of_, compact_block_of_;
  std::vector<int> blocks_;  // compact block of each compact pose
  // The states keep a reference to the layout: it lives at one address for the object's life.
  std::unique_ptr<BlockLayout> layout_;
  std::vector<std::unique_ptr<AgentState>> states_;
};

}  // namespace tessera
