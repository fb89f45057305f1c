#include "transport/message_mapping.hpp"

#include <algorithm>
#include <tessera/graph/flat_measurement.hpp>
#include <tessera/graph/flat_pose.hpp>

namespace tessera::transport {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw TransportError("malformed message: " + what);
}

// The k-th pose of a flat array of poses in SE(d) (graph/flat_pose.hpp).
Pose pose_at(const std::vector<double>& flat, std::size_t k, int d) {
  require((k + 1) * flat_pose_size(d) <= flat.size(), "pose array too short");
  return read_flat_pose(flat, k * flat_pose_size(d), d);
}

}  // namespace

wire::PoseBlock to_wire_block(const PoseBlockMessage& m, const std::string& run_id, bool broadcast,
                              const std::vector<std::uint32_t>& recipients) {
  wire::PoseBlock w;
  w.run_id(run_id);
  w.round(m.round);
  w.sender(m.sender);
  w.phase(m.phase);
  w.broadcast(broadcast);
  w.recipients(recipients);
  w.kind(static_cast<std::uint8_t>(m.kind));
  w.rank(m.rank);
  w.dim(m.dim);
  w.pose_ids(m.pose_ids);
  w.data(m.data);
  return w;
}

wire::RoundStatus to_wire_status(const RoundStatusMessage& m, const std::string& run_id,
                                 bool broadcast, const std::vector<std::uint32_t>& recipients) {
  wire::RoundStatus w;
  w.run_id(run_id);
  w.round(m.round);
  w.sender(m.sender);
  w.broadcast(broadcast);
  w.recipients(recipients);
  w.phase(m.phase);
  w.cost(m.cost);
  w.grad_norm_sq(m.grad_norm_sq);
  w.block_grad_norm(m.block_grad_norm);
  w.restart_vote(m.restart_vote);
  w.done_vote(m.done_vote);
  w.near_bound(m.near_bound);
  w.coarse(m.coarse);
  w.measurement_ids(m.measurement_ids);
  w.weights(m.weights);
  return w;
}

PoseBlockMessage from_wire(const wire::PoseBlock& w) {
  require(w.kind() <= 2, "pose block kind " + std::to_string(w.kind()) + " is not Y, P or V");
  const std::size_t per = static_cast<std::size_t>(w.rank()) * (w.dim() + 1);
  require(w.data().size() == w.pose_ids().size() * per,
          "pose block from agent " + std::to_string(w.sender()) + " has " +
              std::to_string(w.data().size()) + " values for " +
              std::to_string(w.pose_ids().size()) + " poses of rank " + std::to_string(w.rank()) +
              " and dimension " + std::to_string(w.dim()));
  PoseBlockMessage m;
  m.round = w.round();
  m.sender = w.sender();
  m.phase = w.phase();
  m.kind = static_cast<BlockKind>(w.kind());
  m.rank = w.rank();
  m.dim = w.dim();
  m.pose_ids = w.pose_ids();
  m.data = w.data();
  return m;
}

RoundStatusMessage from_wire(const wire::RoundStatus& w) {
  RoundStatusMessage m;
  m.round = w.round();
  m.sender = w.sender();
  m.phase = w.phase();
  m.cost = w.cost();
  m.grad_norm_sq = w.grad_norm_sq();
  m.block_grad_norm = w.block_grad_norm();
  m.restart_vote = w.restart_vote();
  m.done_vote = w.done_vote();
  m.near_bound = w.near_bound();
  m.coarse = w.coarse();
  require(w.weights().size() == w.measurement_ids().size() || w.weights().empty(),
          "status from agent " + std::to_string(w.sender()) + " has " +
              std::to_string(w.weights().size()) + " weights for " +
              std::to_string(w.measurement_ids().size()) + " measurements");
  m.measurement_ids = w.measurement_ids();
  m.weights = w.weights();
  return m;
}

bool addressed_to(bool broadcast, const std::vector<std::uint32_t>& recipients, std::uint32_t me) {
  return broadcast || std::find(recipients.begin(), recipients.end(), me) != recipients.end();
}

wire::MeasurementHandoff to_wire_handoff(
    const std::string& run_id, std::uint32_t sender, std::uint32_t recipient, int d,
    const std::vector<const Measurement*>& measurements,
    const std::vector<std::uint64_t>& measurement_index,
    const std::vector<std::pair<std::uint32_t, const Pose*>>& poses,
    const std::vector<std::pair<std::uint32_t, const Pose*>>& known_poses) {
  wire::MeasurementHandoff w;
  w.run_id(run_id);
  w.sender(sender);
  w.recipient(recipient);
  w.dim(static_cast<std::uint32_t>(d));
  const std::size_t m = measurements.size();
  if (measurement_index.size() != m)
    throw TransportError("hand-off: one index per measurement needed");
  w.meas_index(measurement_index);
  w.meas_i().reserve(m);
  w.meas_j().reserve(m);
  w.meas_R().reserve(m * d * d);
  w.meas_t().reserve(m * d);
  w.meas_kappa().reserve(m);
  w.meas_tau().reserve(m);
  for (const Measurement* e : measurements) {
    w.meas_i().push_back(static_cast<std::uint32_t>(e->i));
    w.meas_j().push_back(static_cast<std::uint32_t>(e->j));
    append_measurement_rt(w.meas_R(), w.meas_t(), *e);
    w.meas_kappa().push_back(e->kappa);
    w.meas_tau().push_back(e->tau);
  }
  w.pose_ids().reserve(poses.size());
  w.pose_data().reserve(poses.size() * flat_pose_size(d));
  for (const auto& [id, pose] : poses) {
    w.pose_ids().push_back(id);
    append_flat_pose(w.pose_data(), *pose);
  }
  if (!known_poses.empty()) {
    w.rank(static_cast<std::uint32_t>(d));
    w.lifted_ids().reserve(known_poses.size());
    w.lifted_data().reserve(known_poses.size() * flat_pose_size(d));
    for (const auto& [id, pose] : known_poses) {
      w.lifted_ids().push_back(id);
      append_flat_pose(w.lifted_data(), *pose);
    }
  }
  return w;
}

HandoffContent from_wire(const wire::MeasurementHandoff& w) {
  const int d = static_cast<int>(w.dim());
  require(d == 2 || d == 3, "hand-off dimension " + std::to_string(w.dim()) + " is not 2 or 3");
  const std::size_t m = w.meas_i().size();
  require(w.meas_index().size() == m && w.meas_j().size() == m && w.meas_R().size() == m * d * d &&
              w.meas_t().size() == m * d && w.meas_kappa().size() == m && w.meas_tau().size() == m,
          "hand-off from agent " + std::to_string(w.sender()) +
              ": measurement arrays differ in length");
  require(w.pose_data().size() == w.pose_ids().size() * flat_pose_size(d),
          "hand-off from agent " + std::to_string(w.sender()) + ": pose arrays differ in length");
  HandoffContent out;
  out.measurement_index = w.meas_index();
  out.measurements.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    Measurement& e = out.measurements[k];
    e.i = w.meas_i()[k];
    e.j = w.meas_j()[k];
    read_measurement_rt(w.meas_R(), k * d * d, w.meas_t(), k * d, d, e);
    e.kappa = w.meas_kappa()[k];
    e.tau = w.meas_tau()[k];
  }
  out.poses.reserve(w.pose_ids().size());
  for (std::size_t k = 0; k < w.pose_ids().size(); ++k)
    out.poses.emplace_back(w.pose_ids()[k], pose_at(w.pose_data(), k, d));
  if (w.purpose() == 0 && !w.lifted_ids().empty()) {
    require(w.rank() == static_cast<std::uint32_t>(d) &&
                w.lifted_data().size() == w.lifted_ids().size() * flat_pose_size(d),
            "hand-off from agent " + std::to_string(w.sender()) +
                ": the known inliers' start arrays differ in length");
    out.known_poses.reserve(w.lifted_ids().size());
    for (std::size_t k = 0; k < w.lifted_ids().size(); ++k)
      out.known_poses.emplace_back(w.lifted_ids()[k], pose_at(w.lifted_data(), k, d));
  }
  return out;
}

std::vector<std::pair<std::uint32_t, Pose>> final_poses(const wire::FinalEstimate& w) {
  const int d = static_cast<int>(w.dim());
  require(d == 2 || d == 3,
          "final estimate dimension " + std::to_string(w.dim()) + " is not 2 or 3");
  require(
      w.pose_data().size() == w.pose_ids().size() * flat_pose_size(d),
      "final estimate from agent " + std::to_string(w.sender()) + ": pose arrays differ in length");
  std::vector<std::pair<std::uint32_t, Pose>> out;
  out.reserve(w.pose_ids().size());
  for (std::size_t k = 0; k < w.pose_ids().size(); ++k)
    out.emplace_back(w.pose_ids()[k], pose_at(w.pose_data(), k, d));
  return out;
}

}  // namespace tessera::transport
