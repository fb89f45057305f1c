#pragma once
// The graph-file options of the commands that read a pose graph (solve, info, plot, eval):
// --keys (how ids name robots) and --stamps (timestamps of the poses).

#include <string>
#include <tessera/io/g2o_reader.hpp>

#include "arguments.hpp"

namespace tessera::cli {

/// Option names with a value ("keys", "stamps"), for Arguments.
extern const char* const kGraphInputOptions[];

/// Help lines for --keys and --stamps.
extern const char* const kGraphInputHelp;

/// Reads `path` (g2o or TORO) with `read` and the options --keys and --stamps of `a`. When
/// the ids were found to name robots (or not to be 0..n-1), says so on stderr.
G2oReadResult read_graph_input(const Arguments& a, const std::string& path,
                               G2oReadOptions read = {});

/// --keys NAME as an option of the reader (auto = nothing).
std::optional<KeyScheme> parse_keys_option(const std::string& name);

}  // namespace tessera::cli
