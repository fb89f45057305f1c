#pragma once
// Wrong loop closures with ground truth, for testing outlier rejection (docs/generator.md,
// "Outliers"). They come from their own random stream and are appended after every clean
// measurement, so the clean graph is the same file without them.

#include <cstddef>
#include <tessera/generate/generator_options.hpp>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>
#include <vector>

#include "generate/noise_model.hpp"
#include "generate/random_stream.hpp"

namespace tessera {

/// Consecutive-pose closures in one group of mutually consistent outliers (the last group
/// may be shorter). Ten, as in the group-outlier experiments of the GNC and PCM papers.
constexpr std::size_t kOutlierGroupSize = 10;

/// `count` wrong measurements between the poses of `truth`. Never between consecutive ids
/// (those are odometry or rendezvous links, which a robust solver treats as known inliers).
/// kRandom: uniform pose pairs, uniformly random rotation, translation uniform in the
/// trajectory's bounding box (at least 1 m per side). kInterRobot: the same, with the two
/// ends on different robots (needs two robots). kGroup: groups (a+k, b+k), k < group size,
/// all measuring the poses b+k as if moved by one random rigid motion, with the usual noise:
/// each group agrees with itself, which a consistency check cannot tell from a true loop.
/// Weights are the noise model's, like the true measurements'.
std::vector<Measurement> sample_outliers(std::size_t count, OutlierKind kind,
                                         const std::vector<Pose>& truth,
                                         const std::vector<std::size_t>& robot_of,
                                         const NoiseModel& noise, RandomStream& random);

}  // namespace tessera
