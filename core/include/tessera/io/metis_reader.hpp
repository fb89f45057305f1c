#pragma once
// Reader for graphs in the METIS / KaHIP text format (as written by gpmetis users and by the
// reference paper's tooling):
//   % comment lines anywhere
//   n m [fmt [ncon]]          header; fmt 0 or 1 (edge weights), 10/11 only with unit vertex
//   weights one line per vertex 1..n: its neighbours (1-based), each followed by a weight when fmt
//   is 1
// An edge given k times (repeated adjacency entries, as the paper's files do for parallel
// measurements) becomes one edge of weight k; with fmt 1 the weights add up. The adjacency must
// be symmetric and hold exactly 2m entries.

#include <string>
#include <tessera/partition/graph_structure.hpp>

namespace tessera {

/// Reads a METIS graph file. Throws InputError "file:line: what" for a missing or malformed
/// header, a vertex id out of range, a self loop, an asymmetric adjacency, a wrong edge count,
/// too few or too many vertex lines, or non-unit vertex weights.
GraphStructure read_metis(const std::string& path);

/// True when the file's first non-comment, non-blank line looks like a METIS header (2 to 4
/// non-negative integers), which a g2o file never has. Used to detect the format by content.
bool looks_like_metis(const std::string& path);

}  // namespace tessera
