#include <algorithm>
#include <deque>
#include <stdexcept>
#include <string>
#include <tessera/online/estimate_extension.hpp>

#include "online/new_pose_adjacency.hpp"

namespace tessera {

EstimateExtension extend_estimate(const PoseGraph& graph, const Eigen::MatrixXd& X,
                                  const std::vector<Pose>& guesses,
                                  std::size_t first_new_measurement) {
  const int d = graph.d;
  const Eigen::Index w = d + 1;
  const Eigen::Index r = X.rows();
  const std::size_t n = graph.num_poses;
  if (r < d || X.cols() % w != 0 || static_cast<std::size_t>(X.cols() / w) > n)
    throw std::invalid_argument("extend_estimate: estimate is " + std::to_string(X.rows()) + " x " +
                                std::to_string(X.cols()) + " for a graph of " + std::to_string(n) +
                                " poses in " + std::to_string(d) + "D");
  if (guesses.size() != n)
    throw std::invalid_argument("extend_estimate: " + std::to_string(guesses.size()) +
                                " guesses for " + std::to_string(n) + " poses");
  const std::size_t m = static_cast<std::size_t>(X.cols() / w);
  EstimateExtension out;
  if (m == n) {
    out.X = X;
    return out;
  }
  out.X.resize(r, w * static_cast<Eigen::Index>(n));
  out.X.leftCols(X.cols()) = X;
  out.X.rightCols(out.X.cols() - X.cols()).setZero();
  const std::size_t first = std::min(first_new_measurement, graph.measurements.size());

  // Adjacency of the new poses only, by new pose k - m.
  const std::vector<std::vector<std::size_t>> touching =
      new_pose_adjacency(graph, m, first_new_measurement);
  // Known: the old poses (every id < m) and the new ones placed so far.
  std::vector<char> placed(n - m, 0);
  auto is_known = [&](std::size_t k) { return k < m || placed[k - m] != 0; };
  auto Y = [&](std::size_t k) { return out.X.middleCols(w * static_cast<Eigen::Index>(k), d); };
  auto p = [&](std::size_t k) { return out.X.col(w * static_cast<Eigen::Index>(k) + d); };

  // Seeds: new poses with a measurement to an old pose, in graph order of that measurement
  // (odometry comes first in a robot's batch, so chains follow their odometry).
  std::deque<std::size_t> queue;
  auto place = [&](std::size_t e, std::size_t target) {
    const Measurement& me = graph.measurements[e];
    if (target == me.j) {  // from i
      Y(me.j) = Y(me.i) * me.R;
      p(me.j) = p(me.i) + Y(me.i) * me.t;
    } else {  // from j: R_i = R_j R_ij^T, t_i = t_j - R_i t_ij
      Y(me.i) = Y(me.j) * me.R.transpose();
      p(me.i) = p(me.j) - Y(me.i) * me.t;
    }
    placed[target - m] = 1;
    queue.push_back(target);
  };
  auto spread = [&]() {
    while (!queue.empty()) {
      const std::size_t k = queue.front();
      queue.pop_front();
      for (std::size_t e : touching[k - m]) {
        const Measurement& me = graph.measurements[e];
        const std::size_t other = me.i == k ? me.j : me.i;
        if (!is_known(other)) {
          place(e, other);
          ++out.composed;
        }
      }
    }
  };
  for (std::size_t e = first; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if (me.i < m && me.j >= m && !is_known(me.j)) {
      place(e, me.j);
      ++out.composed;
    } else if (me.j < m && me.i >= m && !is_known(me.i)) {
      place(e, me.i);
      ++out.composed;
    }
    spread();
  }
  // Pieces with no path to the estimate: start each from its first pose's guess.
  for (std::size_t k = m; k < n; ++k) {
    if (is_known(k)) continue;
    Y(k).setZero();
    Y(k).topRows(d) = guesses[k].R;
    p(k).setZero();
    p(k).head(d) = guesses[k].t;
    placed[k - m] = 1;
    ++out.from_guess;
    queue.push_back(k);
    spread();
  }
  return out;
}

}  // namespace tessera
