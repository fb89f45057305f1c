#pragma once
// The growing pose graph an online run optimises: stream batches (stream_batch.hpp) are
// absorbed into one PoseGraph whose ids are dense in arrival order, so every estimate and
// block layout built so far stays valid when the graph grows (new ids are appended).
//
// A batch is absorbed only after every earlier batch of its robot (sequence numbers without
// gaps); a measurement that names a pose not received yet (another robot's, published late)
// is held and enters with the batch that brings its pose. Anything that cannot be right (a pose
// sent twice, a robot's pose indices out of order, a non-rotation, a measurement to itself, a
// mismatched dimension) throws InputError naming the robot, batch and item.

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/online/stream_batch.hpp>
#include <vector>

namespace tessera {

/// What one call of GraphStream::absorb added (ids of the graph).
struct StreamGrowth {
  std::size_t first_new_pose = 0;  ///< The new poses are [first_new_pose, num_poses).
  std::size_t num_new_poses = 0;
  std::size_t first_new_measurement = 0;  ///< Same for measurements (graph order).
  std::size_t num_new_measurements = 0;
  std::size_t batches = 0;  ///< Batches absorbed (a held-back batch may enter later).

  bool empty() const { return num_new_poses == 0 && num_new_measurements == 0; }
};

class GraphStream {
 public:
  /// `d`: 2 or 3; every batch must match it (InputError otherwise). `source`: names the stream
  /// in error messages (e.g. the replayed file or the DDS topic).
  explicit GraphStream(int d, std::string source = "stream");

  /// Queues `batch`; absorbs it and every queued batch it unblocks (the next sequence numbers
  /// of their robots). Throws InputError for a batch that cannot be right (see above) or a
  /// sequence number that was already received. A refused batch changes nothing and is
  /// dropped: its robot's later batches wait until that sequence number arrives valid.
  StreamGrowth absorb(const StreamBatch& batch);

  const PoseGraph& graph() const { return graph_; }
  /// Robot of each pose id.
  const std::vector<std::uint32_t>& robot_of_pose() const { return robot_of_pose_; }
  const std::vector<PoseKey>& key_of_pose() const { return keys_; }
  /// The front end's guess of each pose (its own frame), by id.
  const std::vector<Pose>& guesses() const { return guesses_; }
  const std::vector<MeasurementKind>& kinds() const { return kinds_; }
  std::optional<std::size_t> id_of(const PoseKey& key) const;
  /// Robots seen so far, in order of their first absorbed pose.
  const std::vector<std::uint32_t>& robots() const { return robots_; }
  /// For the poses from id `first` on: their robot's position in robots() (the block each
  /// robot's agent starts with).
  std::vector<int> robot_blocks_from(std::size_t first) const;
  /// Batches of `robot` absorbed so far (the next expected sequence number). Agents report it
  /// so they can agree on when a batch enters (absorb_gate.hpp).
  std::uint64_t absorbed_batches(std::uint32_t robot) const;
  /// Batches received but waiting for an earlier one of their robot.
  std::size_t queued_batches() const;
  /// Measurements waiting for a pose that has not arrived.
  std::size_t held_measurements() const { return held_.size(); }

 private:
  void absorb_one(const StreamBatch& batch);
  bool try_add(const StreamMeasurement& m);

  std::string source_;
  PoseGraph graph_;
  std::vector<std::uint32_t> robot_of_pose_;
  std::vector<PoseKey> keys_;
  std::vector<Pose> guesses_;
  std::vector<MeasurementKind> kinds_;
  std::map<PoseKey, std::size_t> ids_;
  std::vector<std::uint32_t> robots_;
  std::map<std::uint32_t, std::uint64_t> next_sequence_;
  std::map<std::uint32_t, std::uint64_t> next_index_;
  std::map<std::uint32_t, std::map<std::uint64_t, StreamBatch>> queued_;
  std::vector<StreamMeasurement> held_;
};

}  // namespace tessera
