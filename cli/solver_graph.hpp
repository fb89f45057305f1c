#pragma once
// The graph file of `tessera solve`: g2o or TORO (read_graph_input, with --keys and --stamps),
// or the dpgo measurement CSV (a .csv file or a folder of robot<k>/measurements.csv,
// io/dpgo_csv_reader.hpp), whose is_known_inlier column marks measurements a robust solve
// never rejects.

#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <vector>

#include "arguments.hpp"

namespace tessera::cli {

struct LoadedGraph {
  PoseGraph graph;
  PoseKeys keys;                   ///< CSV: dense ids, the robots of robot_src / robot_dst.
  std::vector<bool> known_inlier;  ///< Per measurement from a CSV file; empty otherwise.
};

/// Reads `path` as dpgo CSV when io's is_dpgo_csv() says so, else with read_graph_input.
LoadedGraph load_graph(const Arguments& a, const std::string& path, const G2oReadOptions& read);

}  // namespace tessera::cli
