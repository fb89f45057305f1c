#pragma once
// The Newton refinement tests' shared set-up: the long chain the block-coordinate rounds are
// slow on, f* to round-off, and the check that every agent takes the same refinement steps
// whatever order the messages arrive in.

#include <cstddef>
#include <cstdint>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::test {

/// A lawnmower-path 3D chain of `poses` poses with at most 4 loop closures (rotation noise 0.1,
/// translation noise 1.0): like parking-garage, the rounds' slow modes are the chain's bending.
PoseGraph refine_chain(std::size_t poses, std::uint64_t seed);

/// f* to round-off (the centralized solver's gradient stop): its default stop may end ~1e-7
/// above f* on long chains, which is not what the refinement is measured against.
double tight_optimum(const PoseGraph& g);

/// Solves `g` in the blocks `parts` with `options` twice, in `options.delivery` order and
/// shuffled (`shuffle_seed`); expects one refinement in each with the same CG iterations and
/// bit for bit the same refined cost and estimate (every sum is taken in agent-id order).
/// Returns the first run.
DistributedResult expect_same_refinement_in_any_delivery_order(const PoseGraph& g,
                                                               const std::vector<int>& parts,
                                                               const DistributedOptions& options,
                                                               std::uint64_t shuffle_seed);

}  // namespace tessera::test
