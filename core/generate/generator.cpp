#include <cmath>
#include <string>
#include <tessera/generate/generator.hpp>

#include "generate/closure_sampling.hpp"
#include "generate/noise_model.hpp"
#include "generate/outlier_sampling.hpp"
#include "generate/random_stream.hpp"
#include "generate/robot_ranges.hpp"
#include "generate/trajectory.hpp"

namespace tessera {
namespace {

// Independent random streams of one seed (stream 1 is the city walk, see trajectory.cpp).
constexpr std::uint64_t kClosureStream = 2;
constexpr std::uint64_t kNoiseStream = 3;
constexpr std::uint64_t kOutlierStream = 4;

std::string describe(const GeneratorOptions& o) {
  return std::string("generated ") + trajectory_kind_name(o.kind) +
         " poses=" + std::to_string(o.num_poses) + " robots=" + std::to_string(o.num_robots) +
         " seed=" + std::to_string(o.seed) + " rot_noise=" + std::to_string(o.rotation_noise) +
         " trans_noise=" + std::to_string(o.translation_noise) +
         (o.outlier_fraction > 0 ? std::string(" outliers=") + std::to_string(o.outlier_fraction) +
                                       " " + outlier_kind_name(o.outlier_kind)
                                 : std::string());
}

// Chain measurements (k, k+1) in id order, composed into the initial guess as they go.
void add_chain(const std::vector<Pose>& truth, const NoiseModel& noise, RandomStream& random,
               GeneratorResult& result) {
  const std::size_t n = truth.size();
  PoseGraph& graph = result.graph;
  graph.initial.reserve(n);
  graph.initial.push_back(truth[0]);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    Measurement m = noisy_measurement(k, k + 1, truth[k], truth[k + 1], noise, random);
    const Pose& prev = graph.initial.back();
    graph.initial.push_back({prev.R * m.R, prev.t + prev.R * m.t});
    graph.measurements.push_back(std::move(m));
    if (result.robot_of[k] == result.robot_of[k + 1])
      ++result.odometry_edges;
    else
      ++result.rendezvous_edges;
  }
}

void add_closures(const std::vector<PosePair>& closures, const std::vector<Pose>& truth,
                  const NoiseModel& noise, RandomStream& random, GeneratorResult& result) {
  for (const auto& [a, b] : closures) {
    result.graph.measurements.push_back(noisy_measurement(a, b, truth[a], truth[b], noise, random));
    if (result.robot_of[a] == result.robot_of[b])
      ++result.intra_robot_closures;
    else
      ++result.inter_robot_closures;
  }
}

void add_outliers(const GeneratorOptions& o, const std::vector<Pose>& truth,
                  const NoiseModel& noise, GeneratorResult& result) {
  const auto count = static_cast<std::size_t>(
      std::llround(o.outlier_fraction * static_cast<double>(result.loop_closures())));
  if (count == 0) return;
  RandomStream random(o.seed, kOutlierStream);
  auto wrong = sample_outliers(count, o.outlier_kind, truth, result.robot_of, noise, random);
  auto& measurements = result.graph.measurements;
  for (auto& m : wrong) {
    result.outliers.push_back(measurements.size());
    measurements.push_back(std::move(m));
  }
}

}  // namespace

GeneratorResult generate_pose_graph(const GeneratorOptions& options) {
  options.validate();
  const std::size_t n = options.num_poses;
  Trajectory trajectory = make_trajectory(options.kind, n, options.seed);

  GeneratorResult result;
  result.robot_of = robot_of_poses(n, options.num_robots);

  RandomStream closure_random(options.seed, kClosureStream);
  const ClosureSampling sampling{options.loop_closure_probability,
                                 options.inter_robot_closure_probability,
                                 options.max_loop_closures};
  std::vector<PosePair> closures =
      sample_closures(trajectory.closure_candidates, result.robot_of, sampling, closure_random);
  trajectory.closure_candidates = {};  // free early: the 1M-pose case is memory-bound

  const NoiseModel noise{options.rotation_noise, options.translation_noise};
  RandomStream noise_random(options.seed, kNoiseStream);
  result.graph.d = trajectory.d;
  result.graph.num_poses = n;
  result.graph.source = describe(options);
  result.graph.measurements.reserve(n - 1 + closures.size());
  add_chain(trajectory.poses, noise, noise_random, result);
  add_closures(closures, trajectory.poses, noise, noise_random, result);
  add_outliers(options, trajectory.poses, noise, result);
  result.ground_truth = std::move(trajectory.poses);
  return result;
}

}  // namespace tessera
