#include "generate/outlier_sampling.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "generate/geometry.hpp"

namespace tessera {
namespace {

// Uniform on SO(d): a uniform angle in 2D, a normalised Gaussian quaternion in 3D.
Eigen::MatrixXd random_rotation(int d, RandomStream& random) {
  if (d == 2) return planar_rotation(2.0 * kPi * random.uniform() - kPi);
  Eigen::Quaterniond q;
  do q.coeffs() << random.normal(), random.normal(), random.normal(), random.normal();
  while (q.norm() < 1e-9);
  return q.normalized().toRotationMatrix();
}

struct Box {
  Eigen::VectorXd lo, size;
};

Box bounding_box(const std::vector<Pose>& truth) {
  Eigen::VectorXd lo = truth.front().t, hi = truth.front().t;
  for (const auto& p : truth) {
    lo = lo.cwiseMin(p.t);
    hi = hi.cwiseMax(p.t);
  }
  return {lo, (hi - lo).cwiseMax(1.0)};
}

Pose random_pose(int d, const Box& box, RandomStream& random) {
  Pose p;
  p.R = random_rotation(d, random);
  p.t = box.lo;
  for (int k = 0; k < d; ++k) p.t(k) += box.size(k) * random.uniform();
  return p;
}

// A uniformly random pair a < b with b > a + 1; with `inter_robot`, on different robots.
std::pair<std::size_t, std::size_t> random_pair(std::size_t n,
                                                const std::vector<std::size_t>& robot_of,
                                                bool inter_robot, RandomStream& random) {
  for (;;) {
    std::size_t a = random.below(n), b = random.below(n);
    if (a > b) std::swap(a, b);
    if (b <= a + 1) continue;
    if (inter_robot && robot_of[a] == robot_of[b]) continue;
    return {a, b};
  }
}

}  // namespace

std::vector<Measurement> sample_outliers(std::size_t count, OutlierKind kind,
                                         const std::vector<Pose>& truth,
                                         const std::vector<std::size_t>& robot_of,
                                         const NoiseModel& noise, RandomStream& random) {
  std::vector<Measurement> out;
  const std::size_t n = truth.size();
  if (count == 0 || n < 3) return out;
  const int d = truth.front().dim();
  const Box box = bounding_box(truth);
  out.reserve(count);
  while (out.size() < count) {
    if (kind != OutlierKind::kGroup) {
      const auto [a, b] = random_pair(n, robot_of, kind == OutlierKind::kInterRobot, random);
      // A random relative pose, drawn as the pose of b seen from the identity.
      const Pose fake = random_pose(d, box, random);
      Measurement m = noisy_measurement(a, b, Pose::identity(d), fake, noise, random);
      out.push_back(std::move(m));
      continue;
    }
    const std::size_t size = std::min(kOutlierGroupSize, count - out.size());
    // Room for the whole group: a + size <= b and b + size <= n.
    if (n < 2 * size + 2) {
      const auto [a, b] = random_pair(n, robot_of, false, random);
      out.push_back(noisy_measurement(a, b, truth[a], random_pose(d, box, random), noise, random));
      continue;
    }
    const std::size_t a = random.below(n - 2 * size - 1);
    const std::size_t b = a + size + 1 + random.below(n - 2 * size - a);
    // One rigid motion M for the whole group: pose b+k is measured as M * truth[b+k].
    const Pose motion = random_pose(d, box, random);
    for (std::size_t k = 0; k < size; ++k) {
      const Pose& t = truth[b + k];
      const Pose moved{motion.R * t.R, motion.R * t.t + (motion.t - box.lo)};
      out.push_back(noisy_measurement(a + k, b + k, truth[a + k], moved, noise, random));
    }
  }
  out.resize(count);
  return out;
}

}  // namespace tessera
