#include "io/g2o_graph_checks.hpp"

#include <algorithm>
#include <optional>
#include <tessera/graph/connectivity.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

namespace tessera {
namespace {

class GraphChecks {
 public:
  GraphChecks(const std::string& name, const G2oReadOptions& options, std::size_t lines,
              const std::vector<std::uint32_t>& edge_lines,
              std::vector<G2oLooseVertex>& loose_vertices, const std::vector<G2oLooseVertex>& fixes,
              G2oReadResult& result)
      : name_(name),
        options_(options),
        allow_disconnected_(options.allow_disconnected),
        fixes_(fixes),
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
    assign_keys();
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
                  " connected components (no chain of edges links pose " +
                  std::to_string(result_.keys.id(outside)) + " to pose " +
                  std::to_string(result_.keys.id(0)) + ")");
  }

 private:
  [[noreturn]] void fail_missing_pose(std::size_t edge, std::uint64_t id) const {
    fail(edge_lines_[edge], "edge to missing pose " + std::to_string(id) +
                                " (the file has VERTEX lines, but none for this id)");
  }

  // Vertices in any order: ids unique, every edge endpoint a vertex; then their poses go to
  // graph.initial by id (ids 0..n-1) or by rank among the ids (any other ids).
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
    auto& initial = result_.graph.initial;
    initial.resize(ids.size());
    if (dense) {
      for (auto& v : loose_) initial[v.id] = std::move(v.pose);
      return n;
    }
    auto& keys = result_.keys.ids;
    keys.resize(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) keys[k] = ids[k].first;
    for (auto& v : loose_) initial[dense_index(v.id)] = std::move(v.pose);
    renumber_edges();
    return ids.size();
  }

  // Dense number of a file id that is in keys.ids.
  std::size_t dense_index(std::uint64_t id) const {
    const auto& keys = result_.keys.ids;
    return static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), id) - keys.begin());
  }

  // Edge endpoints from file ids to dense numbers (keys.ids holds every id).
  void renumber_edges() {
    for (auto& m : result_.graph.measurements) {
      m.i = dense_index(m.i);
      m.j = dense_index(m.j);
    }
  }

  // Robots from the ids (options.keys, or detected), and the fixed pose.
  void assign_keys() {
    auto& g = result_.graph;
    PoseKeys& keys = result_.keys;
    const KeyScheme scheme = options_.keys == KeyScheme::kPlain
                                 ? KeyScheme::kPlain
                                 : detect_key_scheme(keys, g.num_poses);
    assign_robots(keys, g.num_poses, scheme);
    if (scheme != KeyScheme::kPlain) {
      std::string names;
      for (const auto& r : keys.robot_names) names += (names.empty() ? "" : ", ") + r;
      stats().keys_detected =
          std::string(scheme == KeyScheme::kGtsam
                          ? "gtsam keys (robot = character in bits 56-63, index = bits 0-55)"
                          : "gtsam labeled keys (robot = label in bits 48-55, index = bits 0-47)") +
          ": " + std::to_string(keys.num_robots()) + " robots " + names;
    } else if (!keys.ids.empty()) {
      stats().keys_detected = "plain ids (one robot), not 0..n-1: " + std::to_string(g.num_poses) +
                              " ids from " + std::to_string(keys.ids.front()) + " to " +
                              std::to_string(keys.ids.back());
    }
    if (fixes_.empty()) return;
    const std::uint64_t id = fixes_.front().id;
    std::optional<std::size_t> k = keys.find(id);
    if (keys.ids.empty() && id < g.num_poses) k = static_cast<std::size_t>(id);
    if (!k)
      fail(fixes_.front().line,
           "FIX names pose " + std::to_string(id) + ", which no VERTEX or EDGE line has");
    keys.fixed = *k;
  }

  // Without VERTEX lines: the poses are the edge endpoints.
  std::uint64_t check_edge_ids() {
    const auto& ms = result_.graph.measurements;
    std::uint64_t max_id = 0;
    for (const auto& m : ms) max_id = std::max<std::uint64_t>(max_id, std::max(m.i, m.j));
    // 2E endpoints cannot cover more than 2E ids: only then can they be exactly 0..max_id,
    // checked on a bitmap without allocating for a huge id.
    if (max_id < 2 * ms.size()) {
      std::vector<char> seen(max_id + 1, 0);
      for (const auto& m : ms) seen[m.i] = seen[m.j] = 1;
      if (std::find(seen.begin(), seen.end(), 0) == seen.end()) return max_id + 1;
    }
    auto& keys = result_.keys.ids;
    keys.reserve(2 * ms.size());
    for (const auto& m : ms) {
      keys.push_back(m.i);
      keys.push_back(m.j);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    keys.shrink_to_fit();
    renumber_edges();
    return keys.size();
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
  const G2oReadOptions& options_;
  const bool allow_disconnected_;
  const std::vector<G2oLooseVertex>& fixes_;
  const std::size_t lines_;
  const std::vector<std::uint32_t>& edge_lines_;
  std::vector<G2oLooseVertex>& loose_;
  G2oReadResult& result_;
};

}  // namespace

void check_g2o_graph(const std::string& name, const G2oReadOptions& options, std::size_t lines,
                     const std::vector<std::uint32_t>& edge_lines,
                     std::vector<G2oLooseVertex>& loose_vertices,
                     const std::vector<G2oLooseVertex>& fixes, G2oReadResult& result) {
  GraphChecks(name, options, lines, edge_lines, loose_vertices, fixes, result).run();
}

}  // namespace tessera
