#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <tessera/online/graph_stream.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

namespace tessera {

const char* measurement_kind_name(MeasurementKind kind) {
  switch (kind) {
    case MeasurementKind::kOdometry:
      return "odometry";
    case MeasurementKind::kIntraLoop:
      return "intra_loop";
    case MeasurementKind::kInterLoop:
      return "inter_loop";
  }
  return "?";
}

namespace {

std::string key_text(const PoseKey& k) {
  return "(robot " + std::to_string(k.robot) + ", pose " + std::to_string(k.index) + ")";
}

// A rotation the solver can use: d x d, orthonormal to a loose tolerance (front ends send
// doubles that went through their own arithmetic), determinant +1.
bool is_rotation(const Eigen::MatrixXd& R, int d) {
  if (R.rows() != d || R.cols() != d || !R.allFinite()) return false;
  const double err = (R.transpose() * R - Eigen::MatrixXd::Identity(d, d)).norm();
  return err < 1e-6 && R.determinant() > 0;
}

bool is_pose(const Pose& p, int d) {
  return is_rotation(p.R, d) && p.t.size() == d && p.t.allFinite();
}

}  // namespace

GraphStream::GraphStream(int d, std::string source) : source_(std::move(source)) {
  if (d != 2 && d != 3) throw InputError(source_ + ": dimension must be 2 or 3");
  graph_.d = d;
  graph_.source = source_;
}

std::optional<std::size_t> GraphStream::id_of(const PoseKey& key) const {
  auto it = ids_.find(key);
  if (it == ids_.end()) return std::nullopt;
  return it->second;
}

std::vector<int> GraphStream::robot_blocks_from(std::size_t first) const {
  std::vector<int> block;
  for (std::size_t k = first; k < robot_of_pose_.size(); ++k)
    block.push_back(static_cast<int>(std::find(robots_.begin(), robots_.end(), robot_of_pose_[k]) -
                                     robots_.begin()));
  return block;
}

std::uint64_t GraphStream::absorbed_batches(std::uint32_t robot) const {
  auto it = next_sequence_.find(robot);
  return it == next_sequence_.end() ? 0 : it->second;
}

std::size_t GraphStream::queued_batches() const {
  std::size_t n = 0;
  for (const auto& [robot, q] : queued_) n += q.size();
  return n;
}

StreamGrowth GraphStream::absorb(const StreamBatch& batch) {
  const std::string where = source_ + ": robot " + std::to_string(batch.robot) + " batch " +
                            std::to_string(batch.sequence);
  auto& queue = queued_[batch.robot];
  if (batch.sequence < absorbed_batches(batch.robot) || queue.count(batch.sequence))
    throw InputError(where + ": received twice");
  queue.emplace(batch.sequence, batch);

  StreamGrowth growth;
  growth.first_new_pose = graph_.num_poses;
  growth.first_new_measurement = graph_.measurements.size();
  // Absorb this robot's batches while they follow without a gap.
  for (auto it = queue.find(absorbed_batches(batch.robot)); it != queue.end();
       it = queue.find(absorbed_batches(batch.robot))) {
    const StreamBatch next = std::move(it->second);
    queue.erase(it);
    absorb_one(next);
    ++next_sequence_[batch.robot];
    ++growth.batches;
  }
  growth.num_new_poses = graph_.num_poses - growth.first_new_pose;
  growth.num_new_measurements = graph_.measurements.size() - growth.first_new_measurement;
  return growth;
}

void GraphStream::absorb_one(const StreamBatch& batch) {
  const int d = graph_.d;
  const std::string where = source_ + ": robot " + std::to_string(batch.robot) + " batch " +
                            std::to_string(batch.sequence);
  // Check the whole batch first so a bad one leaves the graph as it was.
  auto next_index = next_index_.count(batch.robot) ? next_index_[batch.robot] : 0;
  bool first = !next_index_.count(batch.robot);
  for (std::size_t k = 0; k < batch.poses.size(); ++k) {
    const StreamPose& p = batch.poses[k];
    const std::string item = where + " pose " + std::to_string(k) + " " + key_text(p.key);
    if (p.key.robot != batch.robot)
      throw InputError(item + ": belongs to another robot (a robot publishes its own poses)");
    if (!first && p.key.index < next_index)
      throw InputError(item +
                       ": index not after the robot's previous pose (sent twice or out "
                       "of order)");
    if (!is_pose(p.guess, d))
      throw InputError(item + ": initial guess is not a " + std::to_string(d) +
                       "D pose (rotation not orthonormal with determinant +1, or not finite)");
    next_index = p.key.index + 1;
    first = false;
  }
  for (std::size_t k = 0; k < batch.measurements.size(); ++k) {
    const StreamMeasurement& m = batch.measurements[k];
    const std::string item = where + " measurement " + std::to_string(k) + " " + key_text(m.from) +
                             " -> " + key_text(m.to);
    if (m.from == m.to) throw InputError(item + ": joins a pose to itself");
    if (!is_pose(m.relative, d))
      throw InputError(item + ": relative pose is not a " + std::to_string(d) + "D pose");
    if (!(m.kappa > 0) || !(m.tau > 0) || !std::isfinite(m.kappa) || !std::isfinite(m.tau))
      throw InputError(item + ": weights kappa and tau must be finite and > 0");
  }

  for (const StreamPose& p : batch.poses) {
    ids_.emplace(p.key, graph_.num_poses);
    keys_.push_back(p.key);
    robot_of_pose_.push_back(p.key.robot);
    guesses_.push_back(p.guess);
    graph_.initial.push_back(p.guess);
    ++graph_.num_poses;
    next_index_[batch.robot] = p.key.index + 1;
  }
  if (!batch.poses.empty() &&
      std::find(robots_.begin(), robots_.end(), batch.robot) == robots_.end())
    robots_.push_back(batch.robot);

  // Held measurements first (they were published earlier), then the batch's own.
  std::vector<StreamMeasurement> still_held;
  for (auto& m : held_)
    if (!try_add(m)) still_held.push_back(std::move(m));
  held_ = std::move(still_held);
  for (const StreamMeasurement& m : batch.measurements)
    if (!try_add(m)) held_.push_back(m);
}

bool GraphStream::try_add(const StreamMeasurement& m) {
  const auto i = id_of(m.from), j = id_of(m.to);
  if (!i || !j) return false;
  Measurement e;
  e.i = *i;
  e.j = *j;
  e.R = m.relative.R;
  e.t = m.relative.t;
  e.kappa = m.kappa;
  e.tau = m.tau;
  graph_.measurements.push_back(std::move(e));
  kinds_.push_back(m.kind);
  return true;
}

}  // namespace tessera
