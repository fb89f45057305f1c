#pragma once
// Graph structures with known optimal cuts, shared by the partitioner's tests.

#include <cstddef>

#include "partition/graph_structure.hpp"

namespace tessera::test {

/// A w x h 4-neighbour grid: vertex y * w + x is joined to its right and upper neighbours.
GraphStructure grid_structure(std::size_t w, std::size_t h);

}  // namespace tessera::test
