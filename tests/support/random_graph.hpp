#pragma once
// Small random pose graphs for unit tests (independent of the product's generator, so a
// bug there cannot hide a bug in the solver): a random-walk trajectory with odometry edges,
// random loop closures, and measurements perturbed by noise.

#include <cstdint>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::test {

struct RandomGraphSpec {
  int d = 3;
  std::size_t poses = 30;
  std::size_t loop_closures = 20;
  double rotation_noise = 0.02;     // rad
  double translation_noise = 0.05;  // m
  std::uint64_t seed = 1;
};

/// The graph (with `initial` = ground truth) and, through `truth`, the noise-free poses.
PoseGraph random_pose_graph(const RandomGraphSpec& spec, std::vector<Pose>* truth = nullptr);

}  // namespace tessera::test
