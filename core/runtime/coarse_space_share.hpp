#pragma once
// The part of the smoothed coarse space (distributed/coarse_space.hpp) one agent reads. Every
// agent builds the same space from the whole graph's structure, but an agent other than the
// coarse solver reads the weights of its own poses and of the neighbour copies it holds only:
// its coarse terms, the blend of its poses and copies, and its pieces' list
// (coarse_unknowns_of). The other poses' weights are ~18 bytes a pose of the whole graph in
// every agent (docs/scale.md, "The memory model"); the coarse solver keeps them all, as it
// lists every agent's pieces.

#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera::agent {

/// Keeps in `space` the weight lists of block `agent`'s poses, of the poses its neighbours make
/// public to it (`layout`) and of the other ends of `measurements` that touch the block; the
/// other poses' lists become empty, and the pieces' seeds (CoarseSpace::aggregate, read only
/// while building) are dropped. What the agent reads of the space does not change.
void keep_agent_share(CoarseSpace& space, const BlockLayout& layout, int agent,
                      const std::vector<Measurement>& measurements);

}  // namespace tessera::agent
