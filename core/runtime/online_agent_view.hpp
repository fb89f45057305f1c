#pragma once
// One DDS agent's view of an online run, without DDS (the loop is agent/online_agent.cpp,
// one epoch agent/online_epoch_step.cpp).
// Every agent reads every robot's stream: the graph's structure and measurements are small
// next to the iterates, and an inter-robot closure published by one robot must reach the
// agents of both of its poses. Batches wait in a buffer until all agents hold them: at each
// epoch boundary the agents exchange what they hold (OnlineReport), AbsorbGate takes the
// element-wise minimum, and enter() absorbs exactly those batches in one canonical order
// (stamp, robot, batch), so every agent builds the same graph with the same ids, the same
// blocks (robot-aligned, refined by rebalance_blocks) and the same composed start for the new
// poses, exactly as the in-process engine (online_engine.hpp) does at a step.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <tessera/online/absorb_gate.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/component_alignment.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/linked_problem.hpp>
#include <tessera/online/online_engine.hpp>
#include <vector>

namespace tessera::runtime {

/// What one enter() let in.
struct EnteredData {
  std::size_t batches = 0, poses = 0, measurements = 0;
  std::vector<double> stamps;  ///< Publication stamp of each absorbed batch.
  std::size_t moved = 0;       ///< Poses the rebalance moved to another block.
  std::size_t largest_block = 0;
  std::size_t smallest_block = 0;
  std::size_t cut = 0;  ///< Measurements between two blocks (0: cut refinement off).
  /// New poses placed by composing a new measurement from an estimated pose: when this equals
  /// `measurements`, every new measurement has zero residual at the extended estimate.
  std::size_t composed = 0;
  /// Measurements that linked two pieces of the graph (OnlineOptions::align_merged_pieces).
  std::size_t merges = 0;
};

/// What one take_over() moved.
struct TakeoverMoves {
  std::size_t moved = 0;      ///< Poses of the lost blocks that went to survivor blocks.
  std::size_t cut_after = 0;  ///< Measurements between blocks afterwards.
};

class OnlineAgentView {
 public:
  /// `agent` owns robot `agent`'s block; the run ends once each of robots 0..robots-1 sent its
  /// last batch and it entered. Throws InputError for bad options.
  OnlineAgentView(int agent, int robots, const OnlineOptions& options);

  /// Buffers a received batch (`last`: its robot publishes nothing after it). Throws
  /// InputError for a dimension that differs from earlier batches or a robot >= robots.
  void receive(const StreamBatch& batch, int dim, bool last);
  /// d of the stream, 0 before the first batch.
  int dim() const { return d_; }
  /// Batches held per robot: absorbed plus those buffered without a gap after them.
  Watermarks held() const;
  /// Absorbs the buffered batches below `decision` (AbsorbGate's common watermarks), extends
  /// the estimate to the new poses and rebalances the blocks.
  EnteredData enter(const Watermarks& decision);
  /// Every robot's last batch entered: the stream is over.
  bool stream_over() const;
  /// Batches per robot that entered the graph.
  Watermarks entered() const;
  /// The agents of `lost` robots are gone for good: their blocks' poses go to the survivor
  /// blocks (runtime/online_takeover.hpp) and their robots' future poses to the block that
  /// adopted each. Deterministic: every survivor holding the same graph makes the same moves.
  TakeoverMoves take_over(const std::set<std::uint32_t>& lost);
  /// Robots whose agents were lost (their blocks are empty, their data goes to adopters).
  const std::set<std::uint32_t>& lost() const { return lost_; }
  /// The block that takes lost robot `robot`'s poses, -1 when none has yet.
  int adopter(std::uint32_t robot) const;
  /// Writes a peer's block (stream ids, r*(d+1) values per pose) into the iterate; a larger
  /// rank (the final staircase) widens it.
  void apply_block(const std::vector<std::uint32_t>& ids, const std::vector<double>& data,
                   int rank);
  /// The problem of the next solve (linked poses).
  LinkedProblem problem() const;
  /// Block (robot position in the stream) of this agent's robot, -1 before its first pose.
  int own_block() const;
  /// Block of every stream id (robot-aligned, refined by the rebalance).
  const std::vector<int>& owner() const { return owner_; }

  const GraphStream* stream() const { return stream_ ? &*stream_ : nullptr; }
  Eigen::MatrixXd& iterate() { return X_; }
  const Eigen::MatrixXd& iterate() const { return X_; }
  const OnlineOptions& options() const { return options_; }
  int agent() const { return agent_; }
  int robots() const { return robots_; }

 private:
  bool is_lost_block(int b) const;
  void adopt_lost_poses(std::size_t first_new);
  RebalanceResult rebalance_live_blocks();

  int agent_, robots_, d_ = 0;
  OnlineOptions options_;
  std::optional<GraphStream> stream_;
  std::map<std::uint32_t, std::map<std::uint64_t, StreamBatch>> pending_;
  std::map<std::uint32_t, std::uint64_t> last_count_;  // robot -> its batches (after `last`)
  Eigen::MatrixXd X_;
  std::vector<int> owner_;
  ComponentAlignment pieces_;  // the graph's pieces, aligned when they meet (same on every agent)
  std::set<std::uint32_t> lost_;
  std::map<std::uint32_t, int> adopter_;  // lost robot -> block taking its new poses
};

}  // namespace tessera::runtime
