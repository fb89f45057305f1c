#pragma once
// Internal: the block adjacency (quotient) graph of a partition, its colouring, and a final pass
// that trades a little cut for fewer colours.
//
// IRBCD updates one colour class of the quotient graph per round (blocks of one colour share no
// measurement, so they can move at once). With all N blocks pairwise adjacent every class holds
// one block and a round updates one block; the rounds to a gradient tolerance grow with the
// number of classes far more than with the cut (docs/partitioning.md "Partitions for
// convergence"). The pass merges two colour classes at a time: blocks that would share a colour
// are kept apart by moving the vertices that join them into a third block, then FM refines
// under that constraint.

#include <vector>

#include "partition/kway_refinement.hpp"
#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct QuotientColouring {
  int k = 0;
  std::vector<long long> weight;  ///< k x k: cut weight between two blocks (0 = not adjacent).
  std::vector<int> colour;        ///< A colouring with `colours` colours (colour per block).
  int colours = 0;                ///< Chromatic number (exact unless the search budget ran out).
  int adjacent_pairs = 0;
};

/// The quotient graph of `part` and a minimum colouring (branch and bound, at most
/// `node_budget` search nodes; then the best colouring found, at worst greedy).
QuotientColouring colour_quotient(const WorkGraph& g, const std::vector<int>& part, int k,
                                  long long node_budget = 200000);

struct ColourPassOptions {
  /// The pass keeps a partition with fewer colours only while its cut stays within
  /// (1 + max_cut_increase) x the input's cut. Range 0..10.
  double max_cut_increase = 0.25;
  int min_colours = 2;  ///< Stop once the quotient graph has this many colours (>= 2).
  int tries = 4;        ///< Class pairs tried per merge (the least joined first), >= 1.
  FmParams fm;          ///< Constrained refinement after each merge.
};

struct ColourPassResult {
  int colours_before = 0, colours_after = 0;
  long long cut_before = 0, cut_after = 0;
};

/// Lowers the number of colours of `part`'s quotient graph while the cut allows (see
/// ColourPassOptions), then renumbers the blocks in colour order so that a greedy colouring in
/// block-id order (block_layout.hpp) finds as few colours. The result stays within ub.
ColourPassResult colour_pass(const WorkGraph& g, int k, const std::vector<long long>& ub,
                             std::vector<int>& part, const ColourPassOptions& options, Rng& rng);

}  // namespace tessera::partition_detail
