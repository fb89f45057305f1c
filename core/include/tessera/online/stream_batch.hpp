#pragma once
// What a robot's SLAM front end publishes while it moves (docs/online.md): batches of new
// poses (with their initial guess and timestamp) and new measurements, keyed by robot. The
// DDS message `tessera::wire::GraphStreamBatch` (idl/tessera.idl) carries exactly these
// fields; this is its transport-free form, used by the replay, the stream model and the
// online engine.

#include <cstdint>
#include <tessera/graph/pose.hpp>
#include <vector>

namespace tessera {

/// A pose as a robot names it: the robot and the pose's index along its own trajectory
/// (0, 1, 2, ... in the order the robot creates them). Global ids are assigned by the
/// receiver, so front ends never need to agree on a numbering.
struct PoseKey {
  std::uint32_t robot = 0;
  std::uint64_t index = 0;

  friend bool operator<(const PoseKey& a, const PoseKey& b) {
    return a.robot != b.robot ? a.robot < b.robot : a.index < b.index;
  }
  friend bool operator==(const PoseKey& a, const PoseKey& b) {
    return a.robot == b.robot && a.index == b.index;
  }
};

/// What kind of measurement a front end reports; the solver treats them alike, the kind
/// matters for initialising new poses (odometry first) and for statistics.
enum class MeasurementKind : std::uint8_t {
  kOdometry = 0,   ///< Between consecutive poses of one robot.
  kIntraLoop = 1,  ///< Loop closure between two poses of one robot.
  kInterLoop = 2   ///< Loop closure between poses of two robots.
};

/// "odometry", "intra_loop", "inter_loop".
const char* measurement_kind_name(MeasurementKind kind);

struct StreamPose {
  PoseKey key;
  double stamp = 0.0;  ///< Seconds (the front end's clock) when the pose was created.
  /// The front end's estimate in its own odometry frame. Used only when no measurement links
  /// the pose to an already estimated one (a robot's first poses before any closure).
  Pose guess;
};

struct StreamMeasurement {
  PoseKey from;  ///< The measurement is expressed in this pose's frame (g2o's i).
  PoseKey to;    ///< g2o's j.
  MeasurementKind kind = MeasurementKind::kOdometry;
  double stamp = 0.0;  ///< Seconds when the front end published it.
  Pose relative;       ///< R_ij, t_ij.
  double kappa = 1.0;  ///< Rotation weight (> 0), the convention of graph/measurement.hpp.
  double tau = 1.0;    ///< Translation weight (> 0).
};

/// One publication of one robot. `sequence` counts the robot's batches from 0 without gaps:
/// the receiver absorbs them in that order and can tell when one is missing.
struct StreamBatch {
  std::uint32_t robot = 0;
  std::uint64_t sequence = 0;
  double stamp = 0.0;  ///< Seconds when the batch was published.
  std::vector<StreamPose> poses;
  std::vector<StreamMeasurement> measurements;
};

}  // namespace tessera
