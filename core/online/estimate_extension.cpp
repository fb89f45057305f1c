#include <deque>
#include <stdexcept>
#include <string>
#include <tessera/online/estimate_extension.hpp>

namespace tessera {

EstimateExtension extend_estimate(const PoseGraph& graph, const Eigen::MatrixXd& X,
                                  const std::vector<Pose>& guesses) {
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
  out.X = Eigen::MatrixXd::Zero(r, w * static_cast<Eigen::Index>(n));
  out.X.leftCols(X.cols()) = X;
  if (m == n) return out;

  // Adjacency of the new poses only (measurements among old poses cannot place anything).
  std::vector<std::vector<std::size_t>> touching(n);
  for (std::size_t e = 0; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if (me.i >= m) touching[me.i].push_back(e);
    if (me.j >= m) touching[me.j].push_back(e);
  }
  std::vector<char> known(n, 0);
  std::fill(known.begin(), known.begin() + static_cast<std::ptrdiff_t>(m), 1);
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
    known[target] = 1;
    queue.push_back(target);
  };
  auto spread = [&]() {
    while (!queue.empty()) {
      const std::size_t k = queue.front();
      queue.pop_front();
      for (std::size_t e : touching[k]) {
        const Measurement& me = graph.measurements[e];
        const std::size_t other = me.i == k ? me.j : me.i;
        if (!known[other]) {
          place(e, other);
          ++out.composed;
        }
      }
    }
  };
  for (std::size_t e = 0; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if (me.i < m && me.j >= m && !known[me.j]) {
      place(e, me.j);
      ++out.composed;
    } else if (me.j < m && me.i >= m && !known[me.i]) {
      place(e, me.i);
      ++out.composed;
    }
    spread();
  }
  // Pieces with no path to the estimate: start each from its first pose's guess.
  for (std::size_t k = m; k < n; ++k) {
    if (known[k]) continue;
    Y(k).setZero();
    Y(k).topRows(d) = guesses[k].R;
    p(k).setZero();
    p(k).head(d) = guesses[k].t;
    known[k] = 1;
    ++out.from_guess;
    queue.push_back(k);
    spread();
  }
  return out;
}

}  // namespace tessera
