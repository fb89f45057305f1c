// `tessera plot GRAPH_OR_SOLUTION --out fig.png`: the trajectories seen from above (and in 3D
// for 3D graphs), coloured by robot or by block, with the loop closures. The figure is drawn
// by scripts/plot_trajectories.py (matplotlib) from a JSON file this command writes.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tessera/eval/trajectory_error.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/trajectory_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "commands.hpp"
#include "graph_input.hpp"
#include "json_writer.hpp"
#include "partition_file.hpp"
#include "plot_figure.hpp"

namespace tessera::cli {
namespace {

const char* const kHelp =
    "usage: tessera plot GRAPH_OR_SOLUTION --out fig.png [options]\n"
    "\n"
    "Draws the poses of a graph file with VERTEX lines (g2o or TORO: an input, or the\n"
    "output of tessera solve --out) or of a trajectory (TUM file, folder of per-robot TUM\n"
    "files) seen from above, and for 3D graphs also in 3D: one colour per robot (or per\n"
    "block with --partition), odometry as lines, loop closures as thin lines (inter-robot\n"
    "ones and measurements cut by the partition highlighted, rejected ones in red), the\n"
    "ground truth in grey beside it (aligned onto the estimate). Needs python3-matplotlib.\n"
    "\n"
    "  --out FILE.png          where to write the figure (required)\n"
    "  --partition FILE        block of every pose: one block id per line (tessera\n"
    "                          partition --out) or a JSON object with an \"assignment\" array\n"
    "  --truth FILE            ground truth to draw beside (as tessera eval reads it)\n"
    "  --rejected FILE         measurements rejected as outliers: one measurement index per\n"
    "                          line (tessera solve --robust gnc-tls --rejected), or 'i j'\n"
    "                          (input ids)\n"
    "  --title TEXT            figure title (default: the file name)\n"
    "  --keys auto|plain|gtsam how ids name robots                                [auto]\n"
    "  --stamps FILE           timestamps for the poses of graph inputs ('id stamp'), so\n"
    "                          --truth's alignment matches poses by time, as tessera eval\n"
    "  --help                  this text\n";

// Which measurements were rejected: a line "e" names measurement e (0-based over the EDGE
// lines, as tessera solve --rejected writes), a line "i j" every measurement between the
// poses with input ids i and j.
std::vector<bool> read_rejected(const std::string& path, const PoseGraph& graph,
                                const PoseKeys& keys) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the rejected-measurements file");
  std::set<std::pair<std::uint64_t, std::uint64_t>> pairs;
  std::vector<bool> out(graph.measurements.size(), false);
  std::string line;
  std::size_t number = 0;
  auto number_of = [&](const std::string& tok) {
    char* end = nullptr;
    const unsigned long long v = std::strtoull(tok.c_str(), &end, 10);
    if (tok.empty() || tok[0] == '-' || *end != '\0')
      throw InputError(path, number, "'" + tok + "' is not a non-negative integer");
    return static_cast<std::uint64_t>(v);
  };
  while (std::getline(in, line)) {
    ++number;
    std::istringstream ls(line);
    std::vector<std::string> tok;
    for (std::string t; ls >> t;) tok.push_back(t);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (tok.size() == 1) {
      const std::uint64_t e = number_of(tok[0]);
      if (e >= out.size())
        throw InputError(path, number,
                         "measurement " + tok[0] + " does not exist (the graph has " +
                             std::to_string(out.size()) + ")");
      out[e] = true;
    } else if (tok.size() == 2) {
      const std::uint64_t i = number_of(tok[0]), j = number_of(tok[1]);
      pairs.insert({std::min(i, j), std::max(i, j)});
    } else {
      throw InputError(path, number, "expected a measurement index 'e' or two pose ids 'i j'");
    }
  }
  for (std::size_t e = 0; e < out.size(); ++e) {
    const std::uint64_t a = keys.id(graph.measurements[e].i), b = keys.id(graph.measurements[e].j);
    if (pairs.count({std::min(a, b), std::max(a, b)})) out[e] = true;
  }
  return out;
}

}  // namespace

int run_plot(const Args& args) {
  const Arguments a(args, {"out", "partition", "truth", "rejected", "title", "keys", "stamps"},
                    {"help"});
  if (a.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (a.positional().size() != 1)
    throw InputError("expected one GRAPH_OR_SOLUTION (see tessera plot --help)");
  const auto out = a.get("out");
  if (!out) throw InputError("option --out FILE.png is required (see tessera plot --help)");
  const std::string input = a.positional()[0];

  PlotFigure fig;
  fig.title = a.get_or("title", std::filesystem::path(input).filename().string());
  TrajectoryReadOptions read;
  read.keys = parse_keys_option(a.get_or("keys", "auto"));
  read.stamps = a.get_or("stamps", "");                   // the same matching as tessera eval's
  const Trajectory probe = read_trajectory(input, read);  // any of the accepted inputs
  std::optional<G2oReadResult> graph;
  if (!std::filesystem::is_directory(input)) {
    try {
      G2oReadOptions g;
      g.keys = read.keys;
      g.allow_disconnected = true;
      graph = read_g2o_file(input, g);
    } catch (const InputError&) {
      // Not a graph: a TUM trajectory (probe read it), drawn without measurements.
    }
  }
  if (graph) {
    std::vector<int> blocks;
    if (auto p = a.get("partition")) blocks = read_partition(*p, graph->graph.num_poses);
    std::vector<bool> rejected;
    if (auto p = a.get("rejected")) rejected = read_rejected(*p, graph->graph, graph->keys);
    fig = figure_of_graph(graph->graph, graph->keys, blocks, rejected, fig.title);
  } else {
    if (a.has("partition") || a.has("rejected"))
      throw InputError(input, 0, "--partition and --rejected need a graph file, not a trajectory");
    fig = figure_of_trajectory(probe, fig.title);
  }
  if (auto t = a.get("truth")) {
    const Trajectory truth = read_trajectory(*t, read);
    add_truth(fig, probe, truth);
  }
  draw_figure(fig, *out);
  std::printf("wrote %s\n", out->c_str());
  return 0;
}

}  // namespace tessera::cli
