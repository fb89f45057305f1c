#pragma once
// Shared fixtures of the GNC-TLS tests: small generated graphs with outliers, their robots as
// the blocks, IRBCD inside GNC-TLS, and the odometry as the known inliers.
#include <cstdint>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <vector>

namespace tessera::test {

/// 125-pose 3D grid of 5 robots with `fraction` of its loop closures as random outliers.
GeneratorResult grid_with_outliers(double fraction, std::uint64_t seed = 3);
/// 300-pose 2D city of 5 robots with `fraction` of its loop closures as outliers of `kind`,
/// every measurement's information scaled by 0.03: the file states about 6 times the noise its
/// data has (manhattan3500's states about 9 times). The map is soft: group outliers bend it
/// until some of them fit within the bound, and the rounds' gradient stop leaves the cost
/// further from the optimum than on a file whose information matches its noise.
GeneratorResult flexible_city(double fraction, OutlierKind kind, std::uint64_t seed);
/// The generator's robots as the blocks: robot r owns a contiguous id range.
std::vector<int> robots_as_blocks(const GeneratorResult& r);
/// GNC-TLS around IRBCD, solved to a gradient norm of 1e-3, every solve before the final one by
/// rounds (RobustOptions::refine_passes off).
GncDistributedOptions irbcd_gnc();
/// Per measurement: whether it is odometry (KnownInliers::kOdometry), the known inliers GNC's
/// `known_inlier_flags` take.
std::vector<bool> odometry_flags(const PoseGraph& g);

}  // namespace tessera::test
