#include "plot_figure.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <tessera/eval/trajectory_error.hpp>
#include <tessera/graph/robot_summary.hpp>
#include <tessera/util/input_error.hpp>

#include "json_writer.hpp"

#ifndef TESSERA_SCRIPTS_DIR
#define TESSERA_SCRIPTS_DIR "scripts"
#endif

namespace tessera::cli {
namespace {

Eigen::Vector3d point(const Pose& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  x.head(p.dim()) = p.t;
  return x;
}

std::string points_json(const std::vector<Eigen::Vector3d>& pts, int d) {
  std::string s = "[";
  for (std::size_t k = 0; k < pts.size(); ++k) {
    s += k ? ",[" : "[";
    for (int c = 0; c < d; ++c) s += (c ? "," : "") + json_number(pts[k](c));
    s += "]";
  }
  return s + "]";
}

std::string path_json(const PlotFigure::Path& p, int d) {
  std::string s = "{\"name\":" + json_quote(p.name) + ",\"points\":" + points_json(p.points, d) +
                  ",\"groups\":[";
  for (std::size_t k = 0; k < p.groups.size(); ++k)
    s += (k ? "," : "") + std::to_string(p.groups[k]);
  return s + "]}";
}

std::string figure_json(const PlotFigure& f) {
  std::string s = "{\"title\":" + json_quote(f.title) + ",\"d\":" + std::to_string(f.d) +
                  ",\"color_by\":" + json_quote(f.color_by) + ",\"names\":[";
  for (std::size_t k = 0; k < f.names.size(); ++k) s += (k ? "," : "") + json_quote(f.names[k]);
  s += "],\"paths\":[";
  for (std::size_t k = 0; k < f.paths.size(); ++k)
    s += (k ? ",\n" : "\n") + path_json(f.paths[k], f.d);
  s += "],\"truth\":[";
  for (std::size_t k = 0; k < f.truth.size(); ++k)
    s += (k ? ",\n" : "\n") + path_json(f.truth[k], f.d);
  s += "],\"edges\":[";
  for (std::size_t k = 0; k < f.edges.size(); ++k)
    s += std::string(k ? ",\n" : "\n") + "{\"kind\":" + json_quote(f.edges[k].kind) +
         ",\"a\":" + points_json({f.edges[k].a}, f.d) +
         ",\"b\":" + points_json({f.edges[k].b}, f.d) + "}";
  return s + "]}\n";
}

// The Debian python3 that python3-matplotlib installs into, unless $TESSERA_PYTHON names
// another (a python3 earlier on PATH, e.g. from pyenv, may lack matplotlib).
std::string python_path() {
  if (const char* env = std::getenv("TESSERA_PYTHON")) return env;
  if (std::filesystem::exists("/usr/bin/python3")) return "/usr/bin/python3";
  return "python3";
}

std::string script_path() {
  if (const char* env = std::getenv("TESSERA_PLOT_SCRIPT")) return env;
  return std::string(TESSERA_SCRIPTS_DIR) + "/plot_trajectories.py";
}

}  // namespace

PlotFigure figure_of_graph(const PoseGraph& graph, const PoseKeys& keys,
                           const std::vector<int>& blocks, const std::vector<bool>& rejected,
                           const std::string& title) {
  if (!graph.has_initial())
    throw InputError(graph.source, 0, "has no VERTEX lines: no poses to draw");
  PlotFigure f;
  f.title = title;
  f.d = graph.d;
  f.color_by = blocks.empty() ? "robot" : "block";
  f.paths.resize(keys.num_robots());
  for (std::size_t r = 0; r < f.paths.size(); ++r) f.paths[r].name = keys.robot_name(r);
  int num_blocks = 0;
  for (int b : blocks) num_blocks = std::max(num_blocks, b + 1);
  for (std::size_t k = 0; k < graph.num_poses; ++k) {
    auto& p = f.paths[keys.robot_of(k)];
    p.points.push_back(point(graph.initial[k]));
    p.groups.push_back(blocks.empty() ? static_cast<int>(keys.robot_of(k)) : blocks[k]);
  }
  if (blocks.empty())
    for (std::size_t r = 0; r < f.paths.size(); ++r)
      f.names.push_back("robot " + keys.robot_name(r));
  else
    for (int b = 0; b < num_blocks; ++b) f.names.push_back("block " + std::to_string(b));
  for (std::size_t e = 0; e < graph.measurements.size(); ++e) {
    const Measurement& m = graph.measurements[e];
    std::string kind;
    if (e < rejected.size() && rejected[e])
      kind = "rejected";
    else if (!blocks.empty() && blocks[m.i] != blocks[m.j])
      kind = "cut";
    else if (keys.robot_of(m.i) != keys.robot_of(m.j))
      kind = "inter";
    else {
      const std::uint64_t u = keys.index_in_robot(m.i), v = keys.index_in_robot(m.j);
      if (u + 1 == v || v + 1 == u) continue;  // odometry: drawn as the path
      kind = "intra";
    }
    f.edges.push_back({point(graph.initial[m.i]), point(graph.initial[m.j]), kind});
  }
  return f;
}

PlotFigure figure_of_trajectory(const Trajectory& t, const std::string& title) {
  PlotFigure f;
  f.title = title;
  f.d = t.d;
  for (std::size_t r = 0; r < t.robots.size(); ++r) {
    PlotFigure::Path p;
    p.name = t.robots[r].name;
    for (const auto& q : t.robots[r].poses) {
      p.points.push_back(q.t);
      p.groups.push_back(static_cast<int>(r));
    }
    f.names.push_back(p.name.empty() ? "estimate" : "robot " + p.name);
    f.paths.push_back(std::move(p));
  }
  return f;
}

void add_truth(PlotFigure& fig, const Trajectory& estimate, const Trajectory& truth) {
  Alignment a{Eigen::MatrixXd::Identity(3, 3), Eigen::VectorXd::Zero(3), 1.0};
  try {
    const auto r = trajectory_error(estimate, truth);
    a.R.topLeftCorner(r.d, r.d) = r.alignment.R;
    a.t.head(r.d) = r.alignment.t;
  } catch (const InputError& e) {
    std::fprintf(stderr, "tessera plot: the truth is drawn unaligned: %s\n", e.what());
  }
  // The alignment maps the estimate onto the truth; the truth goes the other way.
  for (const auto& r : truth.robots) {
    PlotFigure::Path p;
    p.name = r.name;
    for (const auto& q : r.poses) p.points.push_back(a.R.transpose() * (q.t - a.t));
    fig.truth.push_back(std::move(p));
  }
}

void draw_figure(const PlotFigure& fig, const std::string& png) {
  const std::string data = png + ".plot.json";
  {
    std::ofstream out(data);
    if (!out) throw InputError(data, 0, "cannot write the figure data");
    out << figure_json(fig);
  }
  const std::string script = script_path();
  if (!std::filesystem::exists(script))
    throw InputError(script, 0, "the plot script is missing (set TESSERA_PLOT_SCRIPT)");
  const std::string python = python_path();
  const pid_t pid = fork();
  if (pid == 0) {
    execlp(python.c_str(), python.c_str(), script.c_str(), data.c_str(), png.c_str(),
           static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0)
    throw InputError(png, 0, "cannot run python3 for the figure");
  std::filesystem::remove(data);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw InputError(png, 0,
                     python + " " + script + " failed (exit " +
                         std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                         "; is python3-matplotlib installed?)");
}

}  // namespace tessera::cli
