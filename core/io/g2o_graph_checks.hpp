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
/// result.graph.measurements (edge e read on line edge_lines[e]) and either graph.initial
/// (vertices in id order) or `loose_vertices` (any order; moved into graph.initial by id).
/// Sets graph.num_poses = 1 + the largest pose id and stats.backward_edges, distinct_pairs,
/// parallel_edges and components. Throws InputError(name, line, what) when the file has no
/// edges, a VERTEX id repeats, an edge names a pose without a VERTEX line (when there are
/// VERTEX lines), an id in 0..n-1 appears on no line, or the graph is disconnected and
/// `allow_disconnected` is false; `line` is the offending line, or 0 for the file as a whole.
void check_g2o_graph(const std::string& name, bool allow_disconnected, std::size_t lines,
                     const std::vector<std::uint32_t>& edge_lines,
                     std::vector<G2oLooseVertex>& loose_vertices, G2oReadResult& result);

}  // namespace tessera
