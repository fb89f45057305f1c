#pragma once
// What `tessera launch` writes from a run on one whole graph file, in the input's ids, frame
// and stamps: --out (g2o), --tum, --tum-dir (one TUM file per robot) and --plot (a figure).
// The coordinator writes the merged poses in the solver's numbering (a TUM file in the run's
// temporary folder); these options turn them back into the input's terms once the run is done.

#include <optional>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <vector>

namespace tessera::cli {

struct LaunchOutputs {
  std::optional<std::string> out, tum, tum_dir, plot;  ///< What to write.
  std::optional<std::string> keys, stamps;             ///< How to read GRAPH (graph_input.hpp).

  bool any() const { return out || tum || tum_dir || plot; }
};

/// Help lines of the options that only launch adds (--tum-dir, --plot, --keys, --stamps).
extern const char* const kLaunchOutputHelp;

/// Takes the LaunchOutputs options out of `argv` (the rest goes to the launch itself).
LaunchOutputs take_launch_outputs(std::vector<std::string>& argv);

/// Reads `graph` with the --keys and --stamps of `outputs` (before the run, so that bad input
/// stops it at once). Throws InputError naming the file and line.
G2oReadResult read_launch_graph(const LaunchOutputs& outputs, const std::string& graph);

/// Reads the merged poses the coordinator wrote as TUM into `merged_tum` (one line per pose,
/// solver order) and writes what `outputs` asks for, in the terms of `input` (read_launch_graph).
/// Throws InputError naming the file on bad input.
void write_launch_outputs(const LaunchOutputs& outputs, const G2oReadResult& input,
                          const std::string& merged_tum);

}  // namespace tessera::cli
