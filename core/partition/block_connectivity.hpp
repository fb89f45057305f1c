#pragma once
// Internal: a vertex's edge weight to each block around it, reused across vertices so that a
// refinement pass allocates once per pass, not once per vertex.

#include <cstddef>
#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct BlockConnectivity {
  std::vector<long long> conn;  ///< conn[b]: weight of v's edges into block b (touched blocks only)
  std::vector<int> touched;     ///< the blocks v touches, each listed once
  explicit BlockConnectivity(int k) : conn(static_cast<std::size_t>(k), 0) {}

  void compute(const WorkGraph& g, const std::vector<int>& part, int v) {
    for (int b : touched) conn[b] = 0;
    touched.clear();
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int b = part[g.adj[e]];
      if (conn[b] == 0) touched.push_back(b);
      conn[b] += g.ew[e];
    }
  }
};

}  // namespace tessera::partition_detail
