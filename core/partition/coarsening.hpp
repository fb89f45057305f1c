#pragma once
// Internal: builds the multilevel hierarchy by repeatedly contracting strongly coupled vertices.

#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct CoarseningParams {
  int stop_vertices = 150;          ///< Stop once a level has at most this many vertices.
  int max_vertex_weight = 1 << 30;  ///< No coarse vertex may grow heavier than this.
  /// Size-constrained label propagation rounds per level; 0 = heavy-edge matching instead.
  int label_propagation_rounds = 0;
};

/// The levels above a fine graph: coarse[0] = contract(fine, maps[0]), coarse[i] =
/// contract(coarse[i-1], maps[i]). Empty when the fine graph is already small enough.
struct Hierarchy {
  std::vector<WorkGraph> coarse;
  std::vector<std::vector<int>> maps;
  const WorkGraph& top(const WorkGraph& fine) const {
    return coarse.empty() ? fine : coarse.back();
  }
};

/// Coarsens `fine`. When `label` is given, only vertices with equal labels are ever contracted
/// (so a partition constant on labels survives on every level: V-cycles and combine). Matching
/// rates an edge by w(u,v)^2 / (c(u) c(v)) (heavy edges between light vertices first) and visits
/// vertices in random order; label propagation moves each vertex to the neighbouring cluster it
/// is most strongly tied to while clusters stay under max_vertex_weight.
Hierarchy coarsen(const WorkGraph& fine, const std::vector<int>* label,
                  const CoarseningParams& params, Rng& rng);

}  // namespace tessera::partition_detail
