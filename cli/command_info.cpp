// `tessera info GRAPH [--json FILE]`: what a g2o pose graph contains, including the quirks
// the reader tolerates (parallel and backward edges, non-PD information matrices).

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <tessera/graph/robot_summary.hpp>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "commands.hpp"
#include "graph_input.hpp"
#include "json_writer.hpp"

namespace tessera::cli {
namespace {

const char* const kHelp =
    "usage: tessera info GRAPH [--json FILE] [--keys auto|plain|gtsam]\n"
    "\n"
    "Reads the pose graph GRAPH (g2o or TORO) and prints its robots (poses, odometry, loop\n"
    "closures inside the robot and with other robots),  poses, edges, dimension, connected "
    "components,\n"
    "parallel edges (measurements on an already-seen unordered pair), backward edges (i > j),\n"
    "information matrices that are not positive definite and whether VERTEX lines exist.\n"
    "A disconnected graph is accepted here (its component count is reported).\n"
    "\n"
    "options:\n"
    "  --json FILE   also write the figures as one JSON object to FILE ('-' for stdout)\n"
    "  --keys auto|plain|gtsam   how pose ids name robots (default auto: detected)\n"
    "  --help        show this text\n"
    "\n"
    "exit status: 0 on success, 2 on bad input (the message names file, line and problem).\n";

std::vector<JsonObject> robot_objects(const RobotSummary& robots) {
  std::vector<JsonObject> out;
  for (const auto& rc : robots.robots) {
    JsonObject o;
    o.add("name", rc.name)
        .add("poses", rc.poses)
        .add("odometry_edges", rc.odometry)
        .add("intra_robot_closures", rc.intra_closures)
        .add("inter_robot_closures", rc.inter_closures);
    out.push_back(o);
  }
  return out;
}

JsonObject info_json(const G2oReadResult& r, const RobotSummary& robots, double load_s) {
  const auto& g = r.graph;
  const auto& s = r.stats;
  JsonObject j;
  j.add("graph", g.source)
      .add("poses", g.num_poses)
      .add("edges", g.num_measurements())
      .add("d", g.d)
      .add("components", s.components)
      .add("distinct_pairs", s.distinct_pairs)
      .add("parallel_edges", s.parallel_edges)
      .add("backward_edges", s.backward_edges)
      .add("non_pd_information", s.non_pd_information)
      .add("first_non_pd_line", s.first_non_pd_line)
      .add("has_vertices", s.vertex_lines > 0)
      .add("vertex_lines", s.vertex_lines)
      .add("fix_lines", s.fix_lines)
      .add("blank_lines", s.blank_lines)
      .add("comment_lines", s.comment_lines)
      .add("max_quaternion_norm_error", s.max_quaternion_norm_error)
      .add("format", s.format)
      .add("keys", key_scheme_name(r.keys.scheme))
      .add("robots", robot_objects(robots))
      .add("odometry_edges", robots.odometry)
      .add("intra_robot_closures", robots.intra_closures)
      .add("inter_robot_closures", robots.inter_closures)
      .add("load_s", load_s);
  return j;
}

// dpgo measurement CSV (a .csv file or a folder of robot<k>/measurements.csv).
int csv_info(const std::string& path, const std::optional<std::string>& json) {
  const auto start = std::chrono::steady_clock::now();
  const DpgoCsvGraph r = read_dpgo_csv(path);
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::size_t known = 0, inter = 0;
  for (std::size_t e = 0; e < r.graph.num_measurements(); ++e) {
    known += r.known_inlier[e] ? 1 : 0;
    const Measurement& m = r.graph.measurements[e];
    inter += r.robot_of[m.i] != r.robot_of[m.j] ? 1 : 0;
  }
  const std::size_t robots =
      r.robot_of.empty() ? 0 : 1 + static_cast<std::size_t>(r.robot_of.back());
  std::printf("graph:                      %s (dpgo measurement CSV)\n", path.c_str());
  std::printf("dimension:                  3D (SE(3))\n");
  std::printf("poses:                      %zu\n", r.graph.num_poses);
  std::printf("edges:                      %zu\n", r.graph.num_measurements());
  std::printf("robots:                     %zu\n", robots);
  std::printf("inter-robot edges:          %zu\n", inter);
  std::printf("known inliers:              %zu\n", known);
  std::printf("duplicate rows skipped:     %zu\n", r.duplicates);
  std::printf("load time:                  %.1f ms\n", load_s * 1e3);
  if (json) {
    JsonObject j;
    j.add("graph", path)
        .add("format", "dpgo-csv")
        .add("poses", r.graph.num_poses)
        .add("edges", r.graph.num_measurements())
        .add("d", 3)
        .add("components", 1)
        .add("robots", robots)
        .add("inter_robot_edges", inter)
        .add("known_inliers", known)
        .add("duplicates", r.duplicates)
        .add("load_s", load_s);
    write_output(*json, j.str());
  }
  return 0;
}

}  // namespace

int run_info(const Args& args) {
  Arguments a(args, {"json", "keys"}, {"help"});
  if (a.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (a.positional().size() != 1)
    throw InputError(std::string(a.positional().empty() ? "missing GRAPH" : "more than one GRAPH") +
                     " (usage: tessera info GRAPH [--json FILE]; see --help)");
  if (is_dpgo_csv(a.positional()[0])) return csv_info(a.positional()[0], a.get("json"));
  G2oReadOptions options;
  options.allow_disconnected = true;
  const auto start = std::chrono::steady_clock::now();
  options.keys = parse_keys_option(a.get_or("keys", "auto"));
  const G2oReadResult r = read_g2o_file(a.positional()[0], options);
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto& g = r.graph;
  const auto& s = r.stats;

  std::printf("graph:                      %s\n", g.source.c_str());
  std::printf("dimension:                  %dD (SE(%d))\n", g.d, g.d);
  std::printf("poses:                      %zu\n", g.num_poses);
  std::printf("edges:                      %zu\n", g.num_measurements());
  std::printf("connected components:       %zu%s\n", s.components,
              s.components > 1 ? "  (disconnected: solvers will refuse this graph)" : "");
  std::printf("distinct pairs:             %zu\n", s.distinct_pairs);
  std::printf("parallel edges:             %zu\n", s.parallel_edges);
  std::printf("backward edges (i > j):     %zu\n", s.backward_edges);
  if (s.non_pd_information > 0)
    std::printf("non-PD information:         %zu  (first on line %zu; weights used as computed)\n",
                s.non_pd_information, s.first_non_pd_line);
  else
    std::printf("non-PD information:         0\n");
  std::printf("VERTEX lines:               %s\n",
              s.vertex_lines > 0 ? std::to_string(s.vertex_lines).c_str()
                                 : "none (initial guess must come from the measurements)");
  if (g.d == 3)
    std::printf("max |quaternion norm - 1|:  %.3g  (normalised)\n", s.max_quaternion_norm_error);
  if (s.blank_lines + s.comment_lines + s.fix_lines > 0)
    std::printf("skipped lines:              %zu blank, %zu comment, %zu FIX\n", s.blank_lines,
                s.comment_lines, s.fix_lines);
  std::printf("format:                     %s, %s ids%s%s\n", s.format.c_str(),
              key_scheme_name(r.keys.scheme), s.keys_detected.empty() ? "" : ": ",
              s.keys_detected.c_str());
  if (r.keys.fixed)
    std::printf("fixed pose (FIX):           %llu\n",
                static_cast<unsigned long long>(r.keys.id(*r.keys.fixed)));
  const RobotSummary robots = summarize_robots(g, r.keys);
  std::printf(
      "robots:                     %zu  (loop closures: %zu intra-robot, %zu inter-robot; "
      "%zu odometry)\n",
      robots.robots.size(), robots.intra_closures, robots.inter_closures, robots.odometry);
  for (const auto& rc : robots.robots)
    std::printf("  robot %-4s %9zu poses, %zu odometry, loop closures: %zu intra / %zu inter\n",
                rc.name.c_str(), rc.poses, rc.odometry, rc.intra_closures, rc.inter_closures);
  std::printf("load time:                  %.1f ms\n", load_s * 1e3);

  if (auto path = a.get("json")) write_output(*path, info_json(r, robots, load_s).str());
  return 0;
}

}  // namespace tessera::cli
