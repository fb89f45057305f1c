#pragma once
// A pose graph: poses 0..n-1 in SE(d) and relative measurements between them.

#include <cstddef>
#include <string>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>
#include <vector>

namespace tessera {

struct PoseGraph {
  int d = 0;                              ///< 2 or 3.
  std::size_t num_poses = 0;              ///< n: ids are 0..n-1.
  std::vector<Measurement> measurements;  ///< In file order.
  /// Initial guess read from VERTEX lines; empty when the file had none (then
  /// initialisation comes from the measurements, e.g. chordal).
  std::vector<Pose> initial;
  std::string source;  ///< Where the graph came from (file path or generator description).

  std::size_t num_measurements() const { return measurements.size(); }
  bool has_initial() const { return initial.size() == num_poses && num_poses > 0; }
};

}  // namespace tessera
