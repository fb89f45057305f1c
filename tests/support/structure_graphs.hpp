#pragma once
// Graph structures with known optimal cuts, and the balance bounds and V-cycle set-up of small
// graphs, shared by the partitioner's tests.

#include <cstddef>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

#include "partition/evolutionary.hpp"
#include "partition/multilevel.hpp"
#include "partition/work_graph.hpp"

namespace tessera::test {

/// A w x h 4-neighbour grid: vertex y * w + x is joined to its right and upper neighbours.
GraphStructure grid_structure(std::size_t w, std::size_t h);

/// A w x h grid plus w h / 4 random short-range chords (loop closures) drawn with std::mt19937
/// from `seed`: irregular enough that seeds and islands find different cuts.
GraphStructure grid_with_chords(std::size_t w, std::size_t h, unsigned seed);

/// The same balance bound for each of the k blocks: (1 + eps) ceil(n / k) vertices.
std::vector<long long> uniform_bounds(const GraphStructure& structure, int k, double eps);

/// A V-cycle for graphs of a few thousand vertices with block bound `ub`: coarsen to 100
/// vertices (coarse vertices below ub / 30), 3 label-propagation rounds, 4 initial runs, flow
/// refinement on the 2 finest levels, default FM everywhere.
partition_detail::CycleParams small_graph_cycle(long long ub);

/// A small memetic search for such graphs: population 3, 12 steps, half of them mutations, the
/// cycle above; nothing else (one island, no polish, no layouts, no re-split).
partition_detail::EvolutionParams small_search(long long ub);

/// Test assertions: `part` gives every vertex of `g` a block in [0, k), and no block outweighs
/// its bound `ub[b]`.
void expect_blocks_within(const partition_detail::WorkGraph& g, const std::vector<int>& part, int k,
                          const std::vector<long long>& ub);

}  // namespace tessera::test
