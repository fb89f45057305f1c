#include <stdexcept>
#include <string>
#include <tessera/graph/flat_pose.hpp>

namespace tessera {

void append_flat_pose(std::vector<double>& out, const Pose& pose, std::size_t width) {
  const std::size_t size = flat_pose_size(pose.dim());
  if (width != 0 && width < size)
    throw std::invalid_argument("flat pose: width " + std::to_string(width) + " < " +
                                std::to_string(size) + " values of a pose");
  const std::size_t start = out.size();
  // Eigen's default storage is column-major, which is the layout.
  out.insert(out.end(), pose.R.data(), pose.R.data() + pose.R.size());
  out.insert(out.end(), pose.t.data(), pose.t.data() + pose.t.size());
  if (width > size) out.resize(start + width, 0.0);
}

Pose read_flat_pose(const std::vector<double>& data, std::size_t offset, int d) {
  const std::size_t dd = static_cast<std::size_t>(d);
  if (offset > data.size() || data.size() - offset < flat_pose_size(d))
    throw std::out_of_range("flat pose: " + std::to_string(data.size()) +
                            " values end before the pose at " + std::to_string(offset) +
                            " (dimension " + std::to_string(d) + ")");
  Pose p;
  p.R = Eigen::Map<const Eigen::MatrixXd>(data.data() + offset, d, d);
  p.t = Eigen::Map<const Eigen::VectorXd>(data.data() + offset + dd * dd, d);
  return p;
}

}  // namespace tessera
