#pragma once
// Internal to the multilevel partitioner: a compact weighted graph (int ids and weights) that
// the coarsening, initial partitioning and refinement phases work on, plus a small seeded RNG
// whose sequence is the same on every platform (so a seed gives the same partition anywhere).

#include <cstdint>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

namespace tessera::partition_detail {

struct WorkGraph {
  int n = 0;
  std::vector<int> xadj;  ///< n+1 offsets.
  std::vector<int> adj;   ///< Neighbour ids (each undirected edge stored twice).
  std::vector<int> ew;    ///< Edge weights.
  std::vector<int> vw;    ///< Vertex weights (number of original vertices contracted into v).
  long long total_vw = 0;

  int degree(int v) const { return xadj[v + 1] - xadj[v]; }
};

/// splitmix64: tiny, fast, good enough for tie breaking and random orders.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, bound), bound >= 1.
  int below(int bound) { return static_cast<int>(next() % static_cast<std::uint64_t>(bound)); }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

WorkGraph to_work_graph(const GraphStructure& g);

/// Contracts `g` along `cluster` (cluster id 0..num_clusters-1 per vertex): vertex weights add
/// up, edges between the same two clusters merge with added weights, edges inside a cluster vanish.
WorkGraph contract(const WorkGraph& g, const std::vector<int>& cluster, int num_clusters);

/// Sum of the weights of edges whose endpoints lie in different blocks.
long long edge_cut(const WorkGraph& g, const std::vector<int>& part);

/// Total vertex weight per block.
std::vector<long long> block_weights(const WorkGraph& g, const std::vector<int>& part, int k);

/// A random permutation of 0..n-1.
std::vector<int> random_order(int n, Rng& rng);

}  // namespace tessera::partition_detail
