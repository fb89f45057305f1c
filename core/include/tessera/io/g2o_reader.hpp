#pragma once
// Reading pose graphs from g2o text files: VERTEX_SE2 / EDGE_SE2 (2D) and
// VERTEX_SE3:QUAT / EDGE_SE3:QUAT (3D). The accepted dialect, the quirks of real benchmark
// files and every error are described in docs/file-formats.md. In short:
//  - Pose ids are any unsigned 64-bit numbers in any order. Ids 0..n-1 are used as they are;
//    other ids are numbered 0..n-1 in increasing order for the solvers and kept in
//    G2oReadResult::keys (with the robot of each pose, graph/pose_keys.hpp).
//    Without VERTEX lines `initial` stays empty; with them, every edge endpoint needs a
//    VERTEX line.
//  - Blank/whitespace-only lines and '#' comment lines are skipped. The first id of the
//    first FIX line becomes keys.fixed (the pose that keeps its VERTEX value).
//  - TORO records (VERTEX2 / EDGE2 / VERTEX3 / EDGE3) are read too, with TORO's order of
//    the information values and its roll-pitch-yaw angles; one file holds one dialect.
//  - Edges are kept exactly as written: backward (i > j) and parallel edges stay as they are.
//  - Edge quaternions are normalised by default; vertex quaternions always are.
//  - Weights (kappa, tau) follow io/information_weights.hpp, also for information matrices
//    that are not positive definite (counted in G2oReadStats); a weight that is not finite
//    and > 0 is an error.
// All problems with the input throw InputError("file:line: what").

#include <cstddef>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>

namespace tessera {

struct G2oReadOptions {
  /// Scale edge quaternions to unit length before converting them to rotations. Off
  /// reproduces solvers that use the raw quaternion in the unit-quaternion formula (the
  /// non-"_qnorm" rows of the reference optima). Vertex quaternions are always normalised.
  bool normalize_quaternions = true;
  /// Accept a graph whose measurements do not connect all poses (e.g. for `tessera info`).
  /// Off by default: a disconnected graph has no unique optimum up to one global gauge.
  bool allow_disconnected = false;

  /// How ids name robots: nothing = detect (gtsam when every id has a letter in its top
  /// byte, else plain); kGtsam refuses an id without one (naming the line); kPlain keeps one
  /// robot whatever the ids look like.
  std::optional<KeyScheme> keys;

  /// Size of the one buffer files and streams are read through, in bytes (1..2^30; a line
  /// longer than it grows it). Small values only serve tests and fuzzing.
  std::size_t read_chunk_bytes = 64 * 1024;

  /// Throws InputError naming the field when an option is out of range.
  void validate() const;
};

/// What was seen while reading, beyond the graph itself.
struct G2oReadStats {
  std::size_t lines = 0;                 ///< Lines in the file (a last line without '\n' counts).
  std::size_t vertex_lines = 0;          ///< VERTEX_SE2 / VERTEX_SE3:QUAT lines.
  std::size_t edge_lines = 0;            ///< EDGE_SE2 / EDGE_SE3:QUAT lines (= measurements).
  std::size_t blank_lines = 0;           ///< Empty or whitespace-only lines (skipped).
  std::size_t comment_lines = 0;         ///< Lines starting with '#' (skipped).
  std::size_t fix_lines = 0;             ///< FIX lines.
  std::size_t backward_edges = 0;        ///< Edges written with i > j.
  std::size_t parallel_edges = 0;        ///< Edges on an unordered pair {i,j} already seen.
  std::size_t distinct_pairs = 0;        ///< Distinct unordered pairs {i,j}.
  std::size_t non_pd_information = 0;    ///< Edges whose full information matrix is not PD.
  std::size_t first_non_pd_line = 0;     ///< Line of the first of those (0 if none).
  std::size_t components = 0;            ///< Connected components of the measurement graph.
  double max_quaternion_norm_error = 0;  ///< max | |q| - 1 | over edge quaternions (3D).
  std::string format = "g2o";            ///< "g2o" or "toro" (by the record tags).
  /// What the key detection found, e.g. "gtsam keys (robot = character in bits 56-63): 2
  /// robots a, b"; empty for ids 0..n-1 read as plain numbers.
  std::string keys_detected;
};

struct G2oReadResult {
  PoseGraph graph;
  PoseKeys keys;  ///< The file's names of the poses (ids, robots, FIX), for writing back.
  G2oReadStats stats;
};

/// Reads the g2o file at `path` (graph.source = path). Throws InputError naming the file,
/// the line and the problem for anything it does not accept, or when the file cannot be read.
G2oReadResult read_g2o_file(const std::string& path, const G2oReadOptions& options = {});

/// Reads g2o text from a stream; `name` stands for the file in messages and graph.source.
G2oReadResult read_g2o_stream(std::istream& in, const std::string& name,
                              const G2oReadOptions& options = {});

/// Reads g2o text held in memory; `name` stands for the file in messages and graph.source.
G2oReadResult read_g2o_text(std::string_view text, const std::string& name,
                            const G2oReadOptions& options = {});

/// Convenience: read_g2o_file(path, options).graph.
PoseGraph read_g2o(const std::string& path, const G2oReadOptions& options = {});

/// Convenience: read_g2o_stream(in, name, options).graph.
PoseGraph read_g2o(std::istream& in, const std::string& name, const G2oReadOptions& options = {});

}  // namespace tessera
