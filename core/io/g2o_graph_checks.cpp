#include "io/g2o_graph_checks.hpp"

#include <algorithm>
#include <tessera/graph/connectivity.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

namespace tessera {
namespace {

class GraphChecks {
 public:
  GraphChecks(const std::string& name, bool allow_disconnected, std::size_t lines,
              const std::vector<std::uint32_t>& edge_lines,
              std::vector<G2oLooseVertex>& loose_vertices, G2oReadResult& result)
      : name_(name),
        allow_disconnected_(allow_disconnected),
        lines_(lines),
        edge_lines_(edge_lines),
        loose_(loose_vertices),
        result_(result) {}

  void run() {
    auto& g = result_.graph;
    if (g.measurements.empty())
      fail(0, lines_ == 0 ? "empty file: no pose-graph edges"
                          : "no edges (EDGE_SE2 or EDGE_SE3:QUAT lines): nothing to optimise");
    std::uint64_t n = 0;
    if (!loose_.empty()) {
      n = check_loose_vertices();
    } else if (stats().vertex_lines > 0) {
      // Vertices 0..n-1 in order: unique and contiguous by construction.
      n = g.initial.size();
      const auto& ms = g.measurements;
      for (std::size_t e = 0; e < ms.size(); ++e)
        for (std::size_t id : {ms[e].i, ms[e].j})
          if (id >= n) fail_missing_pose(e, id);
    } else {
      n = check_edge_ids();
    }
    g.num_poses = static_cast<std::size_t>(n);
    count_pairs();
    const auto labels = connected_components(g);
    std::size_t k = 0, outside = 0;
    for (std::size_t v = 0; v < labels.size(); ++v) {
      if (labels[v] + 1 > k) k = labels[v] + 1;
      if (labels[v] != 0 && outside == 0) outside = v;
    }
    stats().components = k;
    if (k > 1 && !allow_disconnected_)
      fail(0, "the graph is disconnected: " + std::to_string(k) +
                  " connected components (no chain of edges links pose " + std::to_string(outside) +
                  " to pose 0)");
  }

 private:
  [[noreturn]] void fail_missing_pose(std::size_t edge, std::uint64_t id) const {
    fail(edge_lines_[edge], "edge to missing pose " + std::to_string(id) +
                                " (the file has VERTEX lines, but none for this id)");
  }

  // Vertices in any order: ids unique, every edge endpoint a vertex, ids exactly 0..n-1;
  // then their poses go to graph.initial by id.
  std::uint64_t check_loose_vertices() {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> ids;  // (id, line)
    ids.reserve(loose_.size());
    for (const auto& v : loose_) ids.emplace_back(v.id, v.line);
    std::sort(ids.begin(), ids.end());
    std::size_t dup_line = 0, dup_first = 0;
    std::uint64_t dup_id = 0;
    for (std::size_t k = 1; k < ids.size(); ++k) {
      if (ids[k].first == ids[k - 1].first && (dup_line == 0 || ids[k].second < dup_line)) {
        dup_line = ids[k].second;
        dup_first = ids[k - 1].second;
        dup_id = ids[k].first;
      }
    }
    if (dup_line)
      fail(dup_line, "duplicate VERTEX id " + std::to_string(dup_id) + " (first on line " +
                         std::to_string(dup_first) + ")");
    const std::uint64_t n = ids.back().first + 1;
    const bool dense = n == ids.size();
    auto has_vertex = [&](std::uint64_t id) {
      if (dense) return id < n;
      auto it = std::lower_bound(ids.begin(), ids.end(), std::make_pair(id, std::uint32_t{0}));
      return it != ids.end() && it->first == id;
    };
    const auto& ms = result_.graph.measurements;
    for (std::size_t e = 0; e < ms.size(); ++e)
      for (std::size_t id : {ms[e].i, ms[e].j})
        if (!has_vertex(id)) fail_missing_pose(e, id);
    if (!dense) {
      std::uint64_t missing = 0;
      while (missing < ids.size() && ids[missing].first == missing) ++missing;
      fail(0, "pose id " + std::to_string(missing) + " appears on no line, but ids must be 0.." +
                  std::to_string(n - 1) + " (largest VERTEX id " + std::to_string(n - 1) +
                  " on line " + std::to_string(ids.back().second) + ")");
    }
    auto& initial = result_.graph.initial;
    initial.resize(static_cast<std::size_t>(n));
    for (auto& v : loose_) initial[v.id] = std::move(v.pose);
    return n;
  }

  // Without VERTEX lines: n = 1 + the largest edge id and every id 0..n-1 must be used.
  std::uint64_t check_edge_ids() {
    const auto& ms = result_.graph.measurements;
    std::uint64_t max_id = 0;
    std::size_t max_line = 0;
    for (std::size_t e = 0; e < ms.size(); ++e) {
      const std::uint64_t m = std::max(ms[e].i, ms[e].j);
      if (m > max_id || max_line == 0) {
        max_id = m;
        max_line = edge_lines_[e];
      }
    }
    const std::uint64_t n = max_id + 1;
    // 2E endpoints cannot cover more than 2E ids, so a bitmap of 2E + 1 entries always finds
    // the smallest unused id without allocating for a huge bogus id.
    const std::uint64_t limit = std::min<std::uint64_t>(n, 2 * ms.size() + 1);
    std::vector<char> seen(limit, 0);
    for (const auto& m : ms) {
      if (m.i < limit) seen[m.i] = 1;
      if (m.j < limit) seen[m.j] = 1;
    }
    for (std::uint64_t id = 0; id < limit; ++id)
      if (!seen[id])
        fail(0, "pose id " + std::to_string(id) + " appears on no line, but ids must be 0.." +
                    std::to_string(max_id) + " (largest id " + std::to_string(max_id) +
                    " on line " + std::to_string(max_line) + ")");
    return n;
  }

  void count_pairs() {
    const auto& ms = result_.graph.measurements;
    std::vector<std::uint64_t> keys;
    keys.reserve(ms.size());
    for (const auto& m : ms) {
      if (m.i > m.j) ++stats().backward_edges;
      const std::uint64_t a = std::min(m.i, m.j), b = std::max(m.i, m.j);
      keys.push_back(a << 32 | b);
    }
    std::sort(keys.begin(), keys.end());
    const std::size_t distinct = std::unique(keys.begin(), keys.end()) - keys.begin();
    stats().distinct_pairs = distinct;
    stats().parallel_edges = ms.size() - distinct;
  }

  G2oReadStats& stats() { return result_.stats; }

  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw InputError(name_, line, what);
  }

  const std::string& name_;
  const bool allow_disconnected_;
  const std::size_t lines_;
  const std::vector<std::uint32_t>& edge_lines_;
  std::vector<G2oLooseVertex>& loose_;
  G2oReadResult& result_;
};

}  // namespace

void check_g2o_graph(const std::string& name, bool allow_disconnected, std::size_t lines,
                     const std::vector<std::uint32_t>& edge_lines,
                     std::vector<G2oLooseVertex>& loose_vertices, G2oReadResult& result) {
  GraphChecks(name, allow_disconnected, lines, edge_lines, loose_vertices, result).run();
}

}  // namespace tessera
