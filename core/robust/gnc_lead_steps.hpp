#pragma once
// What agent 0 computes over the measurement values the agents send it (GncAgent gathers them):
// the pairwise consistency check of `--robust pcm-gnc` and the fresh start of the kept set.
// Both are global, like the chordal initialization, so they run on one agent.

#include <Eigen/Core>
#include <cstdint>
#include <tessera/graph/measurement.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_local_terms.hpp"

namespace tessera {

/// (file position, value) of each gathered measurement, in any order.
using GatheredValues = std::vector<std::pair<std::uint64_t, Measurement>>;

/// The closures outside the largest consistent set (file positions, ascending), from every
/// measurement of the graph in `values` (consumed). Throws std::runtime_error when some are
/// missing.
std::vector<std::uint64_t> inconsistent_closures(GatheredValues& values, const GncAgentInput& in,
                                                 const GncLocalTerms& terms);

/// The initialization of the kept set (every measurement but the `rejected` ones, in `values`,
/// consumed), lifted to rank `r`: r x (d+1)n, every pose. With `cost` non-null, also its cost
/// over those measurements, summed as the agents' vote sums it (each weight owner's in file
/// order, then the owners' sums in agent-id order: the same bits;
/// RobustOptions::kept_vote_rides_weights). Throws std::runtime_error on a measurement sent twice
/// or a count that does not match.
Eigen::MatrixXd kept_set_start(GatheredValues& values, const GncAgentInput& in,
                               std::size_t rejected, int r, double* cost = nullptr);

/// For every agent, the poses of other agents at the ends of its measurements (ascending), as
/// GncLocalTerms::neighbours() lists them on that agent: what agent 0 sends each agent beside
/// its block of the kept set's start.
std::vector<std::vector<std::size_t>> cut_neighbours(const GncAgentInput& in);

}  // namespace tessera
