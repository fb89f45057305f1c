#pragma once
// What `tessera plot` and `tessera launch --plot` draw, and the drawing: the figure is
// written as JSON and rendered by scripts/plot_trajectories.py with matplotlib (the script
// is found through $TESSERA_PLOT_SCRIPT, else in the source tree this binary was built from;
// the interpreter is $TESSERA_PYTHON, else /usr/bin/python3).

#include <Eigen/Core>
#include <cstdint>
#include <set>
#include <string>
#include <tessera/eval/trajectory.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <utility>
#include <vector>

namespace tessera::cli {

struct PlotFigure {
  std::string title;
  int d = 3;
  std::string color_by = "robot";  ///< "robot" or "block".
  struct Path {
    std::string name;
    std::vector<Eigen::Vector3d> points;  ///< Poses of one robot in order.
    std::vector<int> groups;              ///< Colour group of every point (robot or block).
  };
  std::vector<Path> paths;
  struct Edge {
    Eigen::Vector3d a, b;
    std::string kind;  ///< "intra", "inter", "cut" or "rejected".
  };
  std::vector<Edge> edges;         ///< Loop closures (odometry is the path itself).
  std::vector<Path> truth;         ///< Ground truth, in the estimate's frame.
  std::vector<std::string> names;  ///< Name of every colour group.
};

/// The graph's VERTEX poses per robot with its loop closures: inter-robot, cut by `blocks`
/// (when given: then coloured by block), rejected (rejected[e] for measurement e, when given).
PlotFigure figure_of_graph(const PoseGraph& graph, const PoseKeys& keys,
                           const std::vector<int>& blocks, const std::vector<bool>& rejected,
                           const std::string& title);

/// A trajectory without measurements.
PlotFigure figure_of_trajectory(const Trajectory& trajectory, const std::string& title);

/// Adds `truth`, aligned onto `estimate` (SE(d), matched as tessera eval matches), or as it is
/// when the two do not match.
void add_truth(PlotFigure& fig, const Trajectory& estimate, const Trajectory& truth);

/// Renders the figure into `png`. Throws InputError when python3/matplotlib fail.
void draw_figure(const PlotFigure& fig, const std::string& png);

}  // namespace tessera::cli
