#include "launch_outputs.hpp"

#include <cstdio>
#include <filesystem>
#include <tessera/graph/input_frame.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/trajectory_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "graph_input.hpp"
#include "plot_figure.hpp"
#include "solve_output.hpp"

namespace tessera::cli {

const char* const kLaunchOutputHelp =
    "  --tum-dir DIR        write one TUM file per robot, DIR/robot_<name>.tum (the poses'\n"
    "                       stamps, else their index in the robot, as timestamps)\n"
    "  --plot FILE.png      draw the merged trajectories and loop closures (tessera plot)\n"
    "  --keys auto|plain|gtsam  how GRAPH's ids name robots (auto: detected)       [auto]\n"
    "  --stamps FILE        timestamps of GRAPH's poses ('id stamp', or TUM by order)\n"
    "  (--out, --tum, --tum-dir and --plot use GRAPH's ids and frame: its FIX pose, else\n"
    "   its first pose, keeps its VERTEX value)\n";

LaunchOutputs take_launch_outputs(std::vector<std::string>& argv) {
  LaunchOutputs o;
  std::vector<std::string> rest;
  for (std::size_t k = 0; k < argv.size(); ++k) {
    // `--name value` or `--name=value`, as every other option (cli/arguments.hpp).
    const std::size_t eq = argv[k].find('=');
    const std::string name = argv[k].substr(0, eq);
    std::optional<std::string>* slot = nullptr;
    if (name == "--out") slot = &o.out;
    if (name == "--tum") slot = &o.tum;
    if (name == "--tum-dir") slot = &o.tum_dir;
    if (name == "--plot") slot = &o.plot;
    if (name == "--keys") slot = &o.keys;
    if (name == "--stamps") slot = &o.stamps;
    if (!slot) {
      rest.push_back(argv[k]);
      continue;
    }
    if (*slot) throw InputError("launch: option " + name + " given twice");
    if (eq != std::string::npos) {
      *slot = argv[k].substr(eq + 1);
      continue;
    }
    if (k + 1 >= argv.size()) throw InputError("launch: option " + name + " needs a value");
    *slot = argv[++k];
  }
  argv = std::move(rest);
  return o;
}

namespace {

// The options of `outputs` as a command line (for read_graph_input, write_solution_files).
Arguments as_arguments(const LaunchOutputs& outputs) {
  std::vector<std::string> argv;
  if (outputs.keys) argv.insert(argv.end(), {"--keys", *outputs.keys});
  if (outputs.stamps) argv.insert(argv.end(), {"--stamps", *outputs.stamps});
  if (outputs.out) argv.insert(argv.end(), {"--out", *outputs.out});
  if (outputs.tum) argv.insert(argv.end(), {"--tum", *outputs.tum});
  if (outputs.tum_dir) argv.insert(argv.end(), {"--tum-dir", *outputs.tum_dir});
  return Arguments(argv, {"keys", "stamps", "out", "tum", "tum-dir"}, {});
}

}  // namespace

G2oReadResult read_launch_graph(const LaunchOutputs& outputs, const std::string& graph) {
  return read_graph_input(as_arguments(outputs), graph);
}

void write_launch_outputs(const LaunchOutputs& outputs, const G2oReadResult& input,
                          const std::string& merged_tum) {
  const PoseGraph& g = input.graph;
  const std::string& graph = g.source;
  const Trajectory merged = read_tum_trajectory(merged_tum);
  const auto& rows = merged.robots.front().poses;
  if (rows.size() != g.num_poses)
    throw InputError(merged_tum, 0,
                     "the coordinator wrote " + std::to_string(rows.size()) + " poses for the " +
                         std::to_string(g.num_poses) + " of " + graph);
  std::vector<Pose> poses;
  poses.reserve(rows.size());
  for (const auto& p : rows) poses.push_back({p.R.topLeftCorner(g.d, g.d), p.t.head(g.d)});
  write_solution_files(as_arguments(outputs), g, input.keys, poses);
  if (outputs.plot) {
    PoseGraph shown = g;
    shown.initial = poses;
    move_to_input_frame(g, input.keys, shown.initial);
    draw_figure(
        figure_of_graph(shown, input.keys, {}, {},
                        std::filesystem::path(graph).filename().string() + " (tessera launch)"),
        *outputs.plot);
    std::printf("wrote %s\n", outputs.plot->c_str());
  }
}

}  // namespace tessera::cli
