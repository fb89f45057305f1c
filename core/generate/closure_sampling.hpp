#pragma once
// Choosing which candidate loop closures of a trajectory become measurements.

#include <cstddef>
#include <vector>

#include "generate/random_stream.hpp"
#include "generate/trajectory.hpp"

namespace tessera {

struct ClosureSampling {
  double intra_robot_probability = 0.5;  ///< [0, 1], candidates inside one robot's range
  double inter_robot_probability = 0.5;  ///< [0, 1], candidates between two robots
  std::size_t max_closures = 0;          ///< > 0: keep a uniform random subset of this size
};

/// The accepted candidates, sorted. Each candidate gets one uniform draw from `random` (in
/// candidate order) and is kept when the draw is below its class's probability, so raising
/// a probability only adds closures. A cap then keeps a uniformly random subset.
std::vector<PosePair> sample_closures(const std::vector<PosePair>& candidates,
                                      const std::vector<std::size_t>& robot_of,
                                      const ClosureSampling& sampling, RandomStream& random);

}  // namespace tessera
