#include "random_graph.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace tessera::test {
namespace {

Eigen::MatrixXd random_rotation(int d, double scale, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  if (d == 2) {
    double a = scale * n(rng);
    Eigen::MatrixXd R(2, 2);
    R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    return R;
  }
  Eigen::Vector3d w(n(rng), n(rng), n(rng));
  w *= scale;
  double angle = w.norm();
  if (angle < 1e-15) return Eigen::MatrixXd::Identity(3, 3);
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

}  // namespace

PoseGraph random_pose_graph(const RandomGraphSpec& spec, std::vector<Pose>* truth_out) {
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int d = spec.d;
  std::vector<Pose> truth(spec.poses);
  truth[0] = Pose::identity(d);
  for (std::size_t i = 1; i < spec.poses; ++i) {
    truth[i].R = truth[i - 1].R * random_rotation(d, 0.3, rng);
    Eigen::VectorXd step(d);
    for (int a = 0; a < d; ++a) step(a) = normal(rng);
    truth[i].t = truth[i - 1].t + truth[i - 1].R * step;
  }
  PoseGraph g;
  g.d = d;
  g.num_poses = spec.poses;
  g.source = "random test graph";
  auto add = [&](std::size_t i, std::size_t j) {
    Measurement m;
    m.i = i;
    m.j = j;
    m.R = truth[i].R.transpose() * truth[j].R * random_rotation(d, spec.rotation_noise, rng);
    Eigen::VectorXd noise(d);
    for (int a = 0; a < d; ++a) noise(a) = spec.translation_noise * normal(rng);
    m.t = truth[i].R.transpose() * (truth[j].t - truth[i].t) + noise;
    m.kappa = 1.0 / std::max(1e-4, spec.rotation_noise * spec.rotation_noise);
    m.tau = 1.0 / std::max(1e-4, spec.translation_noise * spec.translation_noise);
    g.measurements.push_back(m);
  };
  for (std::size_t i = 0; i + 1 < spec.poses; ++i) add(i, i + 1);
  std::uniform_int_distribution<std::size_t> pick(0, spec.poses - 1);
  for (std::size_t k = 0; k < spec.loop_closures; ++k) {
    std::size_t i = pick(rng), j = pick(rng);
    if (i == j) continue;
    add(i, j);
  }
  g.initial = truth;
  if (truth_out) *truth_out = truth;
  return g;
}

}  // namespace tessera::test
