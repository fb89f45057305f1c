// grid3d: a lawnmower (boustrophedon) path through a cube lattice, like the grid3D benchmark.
#include <array>

#include "generate/geometry.hpp"
#include "generate/trajectory.hpp"

namespace tessera {
namespace {

using Cell = std::array<std::size_t, 3>;

// Layers in z; inside a layer rows in y alternate direction with the layer, and cells in x
// alternate with the row, so consecutive path indices are always lattice neighbours.
class Lawnmower {
 public:
  explicit Lawnmower(std::size_t side) : s_(side) {}

  Cell cell(std::size_t k) const {
    const std::size_t z = k / (s_ * s_), r = (k / s_) % s_, c = k % s_;
    const std::size_t y = z % 2 == 0 ? r : s_ - 1 - r;
    const std::size_t x = (z * s_ + r) % 2 == 0 ? c : s_ - 1 - c;
    return {x, y, z};
  }

  std::size_t index(const Cell& p) const {
    const std::size_t z = p[2];
    const std::size_t r = z % 2 == 0 ? p[1] : s_ - 1 - p[1];
    const std::size_t c = (z * s_ + r) % 2 == 0 ? p[0] : s_ - 1 - p[0];
    return (z * s_ + r) * s_ + c;
  }

 private:
  std::size_t s_;
};

std::size_t cube_side(std::size_t n) {
  std::size_t s = 1;
  while (s * s * s < n) ++s;
  return s;
}

Eigen::Vector3d position(const Cell& c) {
  return Eigen::Vector3d(double(c[0]), double(c[1]), double(c[2]));
}

// Heading along the path (towards the next pose; the last pose keeps the previous heading);
// vertical steps keep "up" meaningful by taking the y axis as reference.
Eigen::MatrixXd heading_frame(const Eigen::Vector3d& step) {
  const bool vertical = step.z() != 0.0;
  return frame_from_forward_up(step,
                               vertical ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ());
}

}  // namespace

Trajectory make_grid3d_trajectory(std::size_t n) {
  const std::size_t side = cube_side(n);
  const Lawnmower path(side);
  Trajectory traj;
  traj.d = 3;
  traj.poses.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d p = position(path.cell(k));
    const Eigen::Vector3d step =
        k + 1 < n ? position(path.cell(k + 1)) - p : p - position(path.cell(k - 1));
    traj.poses.push_back({heading_frame(step), p});
  }
  traj.closure_candidates.reserve(3 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const Cell c = path.cell(k);
    for (int axis = 0; axis < 3; ++axis) {
      if (c[axis] + 1 >= side) continue;
      Cell neighbour = c;
      ++neighbour[axis];
      traj.closure_candidates.emplace_back(k, path.index(neighbour));
    }
  }
  normalise_candidates(traj.closure_candidates, n);
  return traj;
}

}  // namespace tessera
