// `tessera generate`: writes a synthetic multi-robot pose graph (see docs/generator.md).
#include <chrono>
#include <cstdio>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/stamps_reader.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "robot_files.hpp"

namespace tessera::cli {
namespace {

const char* const kHelp =
    "usage: tessera generate --kind KIND --poses N --out FILE.g2o [options]\n"
    "\n"
    "Writes a synthetic multi-robot pose graph as g2o: a ground-truth trajectory, odometry\n"
    "along it, loop closures where it revisits or passes next to itself, isotropic noise.\n"
    "Robot r of R owns the pose ids [r*N/R, (r+1)*N/R); consecutive robots are always linked\n"
    "by one rendezvous measurement, so the graph is connected. Same options, same bytes.\n"
    "VERTEX lines hold the initial guess (odometry composed from pose 0).\n"
    "\n"
    "  --kind KIND              grid3d | sphere | torus (3D) | city (2D)          [grid3d]\n"
    "  --poses N                number of poses, 2..10000000                      [1000]\n"
    "  --robots R               number of robots, 1..N                            [1]\n"
    "  --seed S                 random seed, integer >= 0                         [1]\n"
    "  --rot-noise RAD          rotation noise std dev per axis, radians, 0..1    [0.01]\n"
    "  --trans-noise M          translation noise std dev per axis, metres, 0..100 [0.05]\n"
    "  --loop-closures P        probability that a candidate closure inside one robot\n"
    "                           is kept, 0..1                                     [0.5]\n"
    "  --inter-robot-closures P same for candidates between two robots, 0..1     [0.5]\n"
    "  --max-loop-closures K    keep at most K sampled closures (0 = no cap)      [0]\n"
    "  --outliers F             add wrong loop closures, F times the number of loop\n"
    "                           closures, 0..0.9, appended after the clean edges  [0]\n"
    "  --outlier-kind KIND      random | group | inter-robot                      [random]\n"
    "                           random: random pose pairs, random relative poses;\n"
    "                           group: groups of 10 mutually consistent wrong closures;\n"
    "                           inter-robot: random, ends on different robots\n"
    "  --labels FILE            write the indices of the added edges (from 0 over the\n"
    "                           EDGE lines) as JSON {\"outliers\": [...]}\n"
    "  --out FILE.g2o           where to write the graph (required)\n"
    "  --truth FILE            also write the ground truth: FILE.g2o = the graph with the\n"
    "                           true poses as VERTEX lines (same ids; what tessera eval\n"
    "                           matches by id), any other name = TUM (plain ids only)\n"
    "  --keys plain|gtsam       pose ids: plain 0..n-1, or gtsam = robot r's pose k as the\n"
    "                           GTSAM key ('a'+r) << 56 | k (up to 26 robots)    [plain]\n"
    "  --stamps FILE            also write a timestamp per pose ('id stamp' lines): 10 Hz\n"
    "                           from t = 1000 s, every robot starting at once (plain ids:\n"
    "                           one clock along the ids)\n"
    "  --json FILE              also write a JSON summary\n"
    "  --split DIR              also write one file per robot, DIR/robot<r>.g2o: its poses'\n"
    "                           VERTEX lines and the measurements it recorded, global ids\n"
    "                           (for tessera launch DIR / tessera-agent --graph FILE)\n"
    "  --help                   this text\n"
    "\n"
    "Weights: kappa = 1/(2 rot_noise^2), tau = 1/trans_noise^2 (noise floored at 1e-3).\n";

std::size_t get_count(const Arguments& args, const std::string& name, long fallback) {
  const long v = args.get_long(name, fallback);
  if (v < 0)
    throw InputError("option --" + name + ": must not be negative (got " + std::to_string(v) + ")");
  return static_cast<std::size_t>(v);
}

GeneratorOptions parse_options(const Arguments& args) {
  GeneratorOptions o;
  o.kind = parse_trajectory_kind(args.get_or("kind", trajectory_kind_name(o.kind)));
  o.num_poses = get_count(args, "poses", static_cast<long>(o.num_poses));
  o.num_robots = get_count(args, "robots", static_cast<long>(o.num_robots));
  o.seed = get_count(args, "seed", static_cast<long>(o.seed));
  o.rotation_noise = args.get_double("rot-noise", o.rotation_noise);
  o.translation_noise = args.get_double("trans-noise", o.translation_noise);
  o.loop_closure_probability = args.get_double("loop-closures", o.loop_closure_probability);
  o.inter_robot_closure_probability =
      args.get_double("inter-robot-closures", o.inter_robot_closure_probability);
  o.max_loop_closures = get_count(args, "max-loop-closures", 0);
  o.outlier_fraction = args.get_double("outliers", o.outlier_fraction);
  o.outlier_kind =
      parse_outlier_kind(args.get_or("outlier-kind", outlier_kind_name(o.outlier_kind)));
  return o;
}

// Robot r's k-th pose becomes the GTSAM key ('a' + r) << 56 | k.
void name_by_robot(const GeneratorResult& result, std::size_t num_robots, PoseKeys& keys) {
  if (num_robots > 26) throw InputError("option --keys gtsam: at most 26 robots (a..z)");
  keys.ids.resize(result.graph.num_poses);
  std::size_t begin = 0;
  for (std::size_t k = 0; k < keys.ids.size(); ++k) {
    if (k > 0 && result.robot_of[k] != result.robot_of[k - 1]) begin = k;
    keys.ids[k] = gtsam_key(static_cast<char>('a' + result.robot_of[k]), k - begin);
  }
  assign_robots(keys, result.graph.num_poses, KeyScheme::kGtsam);
}

// 10 Hz from t = 1000 s: every robot starts at once (its index), plain ids along the ids.
void stamp_poses(std::size_t num_poses, PoseKeys& keys) {
  keys.stamps.resize(num_poses);
  for (std::size_t k = 0; k < keys.stamps.size(); ++k)
    keys.stamps[k] = 1000.0 + 0.1 * static_cast<double>(keys.index_in_robot(k));
}

void write_truth(const GeneratorResult& result, const PoseKeys& keys, const std::string& path) {
  const bool g2o = path.size() >= 4 && path.compare(path.size() - 4, 4, ".g2o") == 0;
  if (g2o) return write_g2o(result.graph, keys, result.ground_truth, path);
  if (keys.scheme != KeyScheme::kPlain)
    throw InputError(
        "option --truth: a TUM file cannot tell the robots of GTSAM keys apart; "
        "give a name ending in .g2o");
  write_tum(result.ground_truth, path);
}

struct Timing {
  double generate_s = 0, write_s = 0;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void write_json(const std::string& path, const GeneratorOptions& o, const GeneratorResult& r,
                const std::string& graph_path, const Timing& timing) {
  JsonObject j;
  j.add("kind", trajectory_kind_name(o.kind))
      .add("graph", graph_path)
      .add("d", r.graph.d)
      .add("poses", r.graph.num_poses)
      .add("edges", r.graph.num_measurements())
      .add("robots", o.num_robots)
      .add("seed", static_cast<std::size_t>(o.seed))
      .add("odometry_edges", r.odometry_edges)
      .add("loop_closures", r.loop_closures())
      .add("intra_robot_closures", r.intra_robot_closures)
      .add("inter_robot_closures", r.inter_robot_closures)
      .add("rendezvous_edges", r.rendezvous_edges)
      .add("rotation_noise", o.rotation_noise)
      .add("translation_noise", o.translation_noise)
      .add("loop_closure_probability", o.loop_closure_probability)
      .add("inter_robot_closure_probability", o.inter_robot_closure_probability)
      .add("max_loop_closures", o.max_loop_closures)
      .add("outlier_fraction", o.outlier_fraction)
      .add("outlier_kind", outlier_kind_name(o.outlier_kind))
      .add("outliers", r.outliers.size())
      .add("kappa", r.graph.measurements.front().kappa)
      .add("tau", r.graph.measurements.front().tau)
      .add("generate_s", timing.generate_s)
      .add("write_s", timing.write_s);
  write_output(path, j.str());
}

}  // namespace

int run_generate(const Args& argv) {
  const Arguments args(
      argv,
      {"kind", "poses", "robots", "seed", "rot-noise", "trans-noise", "loop-closures",
       "inter-robot-closures", "max-loop-closures", "outliers", "outlier-kind", "labels", "out",
       "truth", "json", "split", "keys", "stamps"},
      {"help"});
  if (args.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (!args.positional().empty())
    throw InputError("unexpected argument '" + args.positional().front() + "' (see --help)");
  const auto out = args.get("out");
  if (!out) throw InputError("option --out FILE.g2o is required (see --help)");

  const GeneratorOptions options = parse_options(args);
  Timing timing;
  auto start = std::chrono::steady_clock::now();
  const GeneratorResult result = generate_pose_graph(options);
  const std::string keys = args.get_or("keys", "plain");
  if (keys != "plain" && keys != "gtsam")
    throw InputError("option --keys: '" + keys + "' is not one of plain, gtsam");
  PoseKeys pose_keys;
  if (keys == "gtsam") name_by_robot(result, options.num_robots, pose_keys);
  if (args.has("stamps")) stamp_poses(result.graph.num_poses, pose_keys);
  timing.generate_s = seconds_since(start);
  start = std::chrono::steady_clock::now();
  write_g2o(result.graph, pose_keys, result.graph.initial, *out);
  timing.write_s = seconds_since(start);  // the g2o file only
  if (auto truth = args.get("truth")) write_truth(result, pose_keys, *truth);
  if (auto stamps = args.get("stamps"))
    write_stamps_file(pose_keys, result.graph.num_poses, *stamps);
  if (auto json = args.get("json")) write_json(*json, options, result, *out, timing);
  if (auto labels = args.get("labels"))
    write_output(*labels, JsonObject().add("outliers", result.outliers).str());
  if (auto split = args.get("split")) {
    if (keys == "gtsam")
      throw InputError("option --split writes ids 0..n-1: not with --keys gtsam");
    const auto files = write_robot_files(*out, result.graph.num_poses, options.num_robots, *split);
    std::printf("wrote %zu robot files into %s\n", files.size(), split->c_str());
  }

  const std::string outliers =
      result.outliers.empty() ? "" : ", " + std::to_string(result.outliers.size()) + " outliers";
  std::printf(
      "generated %s: %zu poses, %zu edges, %zu robots, %zu loop closures (%zu intra-robot, %zu "
      "inter-robot, %zu rendezvous), %zu odometry%s -> %s\n",
      trajectory_kind_name(options.kind), result.graph.num_poses, result.graph.num_measurements(),
      options.num_robots, result.loop_closures(), result.intra_robot_closures,
      result.inter_robot_closures, result.rendezvous_edges, result.odometry_edges, outliers.c_str(),
      out->c_str());
  return 0;
}

}  // namespace tessera::cli
