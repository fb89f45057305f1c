#pragma once
// What a pose graph read from a g2o file must satisfy once its last line is read, and the
// statistics that need the whole graph. Split from the line parser (g2o_reader.cpp): the
// parser collects records, these checks decide whether they form a graph.

#include <cstdint>
#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <vector>

namespace tessera {

/// A VERTEX record that did not arrive in id order 0, 1, 2, ... (rare; the reader then keeps
/// every vertex in this form until the checks sort them).
struct G2oLooseVertex {
  std::uint64_t id;
  std::uint32_t line;
  Pose pose;
};

/// Completes `result` after the last of `lines` lines of the file `name` was parsed into
/// result.graph.measurements (edge e read on line edge_lines[e], endpoints as the file's ids)
/// and either graph.initial (vertices in id order 0, 1, ...) or `loose_vertices` (any ids,
/// any order). Numbers the poses 0..n-1 (ids 0..n-1 stay as they are; any other ids in
/// increasing order, kept in result.keys.ids), assigns robots by options.keys (detected
/// when unset; stats.keys_detected says what was found), maps the first of `fixes` (a
/// FIX id and its line) to result.keys.fixed, and sets stats.backward_edges,
/// distinct_pairs, parallel_edges and components. Throws InputError(name, line, what) when
/// the file has no edges, a VERTEX id repeats, an edge names a pose without a VERTEX line
/// (when there are VERTEX lines), a FIX id names no pose, or the graph is disconnected and
/// options.allow_disconnected is false; `line` is the offending line, or 0 for the file.
void check_g2o_graph(const std::string& name, const G2oReadOptions& options, std::size_t lines,
                     const std::vector<std::uint32_t>& edge_lines,
                     std::vector<G2oLooseVertex>& loose_vertices,
                     const std::vector<G2oLooseVertex>& fixes, G2oReadResult& result);

}  // namespace tessera
