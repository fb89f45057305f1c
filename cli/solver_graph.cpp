#include "solver_graph.hpp"

#include <tessera/io/dpgo_csv_reader.hpp>

#include "graph_input.hpp"

namespace tessera::cli {

LoadedGraph load_graph(const Arguments& a, const std::string& path, const G2oReadOptions& read) {
  if (is_dpgo_csv(path)) {
    DpgoCsvGraph csv = read_dpgo_csv(path);
    LoadedGraph out{std::move(csv.graph), {}, std::move(csv.known_inlier)};
    const int robots = csv.robot_of.empty() ? 0 : csv.robot_of.back() + 1;
    out.keys.robot.assign(csv.robot_of.begin(), csv.robot_of.end());
    for (int r = 0; r < robots; ++r) out.keys.robot_names.push_back(std::to_string(r));
    return out;
  }
  G2oReadResult input = read_graph_input(a, path, read);
  return {std::move(input.graph), std::move(input.keys), {}};
}

}  // namespace tessera::cli
