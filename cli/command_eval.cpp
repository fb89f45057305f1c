// `tessera eval EST GROUND_TRUTH`: accuracy of an estimate against ground truth (ATE after
// alignment, RPE over --delta poses), per robot and over the team.

#include <cstdio>
#include <string>
#include <tessera/eval/trajectory_error.hpp>
#include <tessera/io/trajectory_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "commands.hpp"
#include "graph_input.hpp"
#include "json_writer.hpp"

namespace tessera::cli {
namespace {

const char* const kHelp =
    "usage: tessera eval EST GROUND_TRUTH [--align se3|sim3|none] [--delta K] [--json FILE]\n"
    "\n"
    "Compares the estimated trajectory EST with GROUND_TRUTH. Each is a graph file with\n"
    "VERTEX lines (g2o or TORO; e.g. tessera solve --out, or tessera generate --truth\n"
    "FILE.g2o), a TUM file, or a folder of per-robot TUM files (tessera solve/launch\n"
    "--tum-dir). Robots match by name, poses by timestamp (both sides stamped) or by index.\n"
    "  ATE: position error after the best alignment of the whole estimate onto the truth\n"
    "       (Umeyama; SE(2) for 2D trajectories), RMSE / mean / median / max, metres.\n"
    "  RPE: translation error of the motion from pose k to pose k + K of one robot, metres.\n"
    "\n"
    "  --align se3|sim3|none   alignment of the estimate (sim3 adds a scale)       [se3]\n"
    "  --delta K               RPE step in poses, >= 1                              [1]\n"
    "  --tolerance S           largest stamp difference of matched poses, seconds  [0.01]\n"
    "  --json FILE             also write {ate, rpe, ...} as JSON ('-' for stdout)\n"
    "  --keys auto|plain|gtsam how graph ids name robots                          [auto]\n"
    "  --stamps FILE           timestamps for the poses of graph inputs ('id stamp')\n"
    "  --help                  this text\n";

JsonObject stats_json(const ErrorStats& s) {
  JsonObject j;
  j.add("rmse", s.rmse)
      .add("mean", s.mean)
      .add("median", s.median)
      .add("max", s.max)
      .add("count", s.count);
  return j;
}

JsonObject metric_json(const TrajectoryErrorResult& r, bool ate) {
  JsonObject j = stats_json(ate ? r.ate : r.rpe);
  std::vector<JsonObject> robots;
  for (const auto& re : r.robots) {
    JsonObject o = stats_json(ate ? re.ate : re.rpe);
    o.add("name", re.name);
    robots.push_back(o);
  }
  j.add("robots", robots);
  return j;
}

}  // namespace

int run_eval(const Args& args) {
  const Arguments a(args, {"align", "delta", "tolerance", "json", "keys", "stamps"}, {"help"});
  if (a.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (a.positional().size() != 2)
    throw InputError("expected EST and GROUND_TRUTH (see tessera eval --help)");
  TrajectoryErrorOptions opt;
  opt.align = parse_align_mode(a.get_or("align", "se3"));
  const long delta = a.get_long("delta", 1);
  if (delta < 1) throw InputError("option --delta: must be >= 1, got " + std::to_string(delta));
  opt.delta = static_cast<std::size_t>(delta);
  opt.stamp_tolerance = a.get_double("tolerance", opt.stamp_tolerance);
  opt.validate();
  TrajectoryReadOptions read;
  read.keys = parse_keys_option(a.get_or("keys", "auto"));
  read.stamps = a.get_or("stamps", "");
  const Trajectory est = read_trajectory(a.positional()[0], read);
  const Trajectory truth = read_trajectory(a.positional()[1], read);
  const TrajectoryErrorResult r = trajectory_error(est, truth, opt);

  std::printf(
      "%s vs %s: %zu poses matched by %s (%zu of the estimate unmatched), %dD, "
      "alignment %s%s\n",
      est.source.c_str(), truth.source.c_str(), r.matched, r.matched_by.c_str(),
      r.unmatched_estimate, r.d, align_mode_name(opt.align),
      opt.align == AlignMode::kSim3 ? (" (scale " + std::to_string(r.alignment.scale) + ")").c_str()
                                    : "");
  std::printf("%-10s %8s %12s %12s %12s %12s   %12s %12s\n", "robot", "poses", "ATE rmse",
              "ATE mean", "ATE median", "ATE max", "RPE rmse", "RPE max");
  auto row = [](const std::string& name, std::size_t n, const ErrorStats& ate,
                const ErrorStats& rpe) {
    std::printf("%-10s %8zu %12.6g %12.6g %12.6g %12.6g   %12.6g %12.6g\n", name.c_str(), n,
                ate.rmse, ate.mean, ate.median, ate.max, rpe.rmse, rpe.max);
  };
  for (const auto& re : r.robots) row(re.name.empty() ? "-" : re.name, re.matched, re.ate, re.rpe);
  row("team", r.matched, r.ate, r.rpe);

  if (auto path = a.get("json")) {
    JsonObject j;
    j.add("estimate", est.source)
        .add("ground_truth", truth.source)
        .add("align", align_mode_name(opt.align))
        .add("scale", r.alignment.scale)
        .add("delta", opt.delta)
        .add("d", r.d)
        .add("matched_by", r.matched_by)
        .add("matched", r.matched)
        .add("unmatched_estimate", r.unmatched_estimate)
        .add("ate", metric_json(r, true))
        .add("rpe", metric_json(r, false));
    write_output(*path, j.str());
  }
  return 0;
}

}  // namespace tessera::cli
