#pragma once
// What `tessera solve` writes, whichever algorithm ran: the poses file (--out) and the
// fields its JSON summary (--json) begins with. Shared by the centralized path
// (command_solve.cpp) and the distributed one (solve_distributed.cpp) so both keep one
// public format.

#include <optional>
#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

#include "arguments.hpp"
#include "json_writer.hpp"

namespace tessera::cli {

/// Writes `poses` to `path`: TUM text when the name ends in ".tum", otherwise a g2o file
/// with the vertices and `graph`'s edges (with the ids of `keys`). Throws InputError naming
/// the path if it cannot.
void write_poses(const std::string& path, const PoseGraph& graph, const std::vector<Pose>& poses,
                 const PoseKeys& keys = {});

/// Help lines for --out, --tum and --tum-dir.
extern const char* const kSolutionOutputHelp;

/// Moves `poses` into the input's frame (graph/input_frame.hpp) and writes the files that
/// options --out, --tum and --tum-dir of `a` ask for, with the input's ids and stamps.
void write_solution_files(const Arguments& a, const PoseGraph& graph, const PoseKeys& keys,
                          std::vector<Pose> poses);

/// The result fields every solver reports.
struct SolveSummary {
  std::string algorithm;          ///< "centralized", "rbcd", "rbcd++" or "irbcd".
  int rank = 0;                   ///< Relaxation rank r of the (last) solve.
  int iterations = 0;             ///< Solver iterations (centralized) or rounds (distributed).
  double grad_norm = 0;           ///< Riemannian gradient norm at the end.
  double cost = 0;                ///< f of the rounded poses.
  double relaxation_cost = 0;     ///< f of the lifted solution.
  std::optional<bool> certified;  ///< Empty when no certificate was computed.
};

/// A JSON object whose first fields are, in this order: algorithm, graph (= graph_path),
/// poses, edges, d, rank, iterations, grad_norm, cost, relaxation_cost, certified. Callers
/// append their algorithm's own fields after these.
JsonObject solve_json(const std::string& graph_path, const PoseGraph& graph,
                      const SolveSummary& summary);

}  // namespace tessera::cli
