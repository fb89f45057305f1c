#pragma once
// Quality figures of a partition of a GraphStructure into N blocks, counted the way the
// partitioning literature (and the reference paper) counts them.

#include <cstddef>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

namespace tessera {

struct PartitionMetrics {
  std::size_t parts = 0;         ///< N.
  std::size_t num_vertices = 0;  ///< n.
  std::size_t cut_edges = 0;  ///< Measurements between different blocks (sum of cut edge weights).
  std::size_t cut_pairs = 0;  ///< Distinct vertex pairs between different blocks.
  std::vector<std::size_t> block_sizes;  ///< Vertices per block (N entries).
  std::size_t max_block = 0;             ///< Largest block.
  double imbalance = 0.0;        ///< max_block / (n/N) - 1 (KaHIP's and the paper's definition).
  double max_block_ratio = 0.0;  ///< max_block / ceil(n/N); the balance constraint is <= 1 + eps.
  /// Communication volume factor: (sum over v of the number of blocks other than v's in which v
  /// has a neighbour) / n.
  double cvolume = 0.0;
  std::size_t boundary_vertices = 0;  ///< Vertices with a neighbour in another block.
};

/// Computes the metrics of `assignment` (block id per vertex, 0..parts-1). Throws InputError
/// when the assignment has the wrong length or a block id out of range.
PartitionMetrics compute_partition_metrics(const GraphStructure& graph,
                                           const std::vector<int>& assignment, int parts);

/// The balance bound: floor((1 + eps) * ceil(n / parts)), the most vertices one block may hold.
std::size_t max_block_size(std::size_t n, int parts, double eps);

}  // namespace tessera
