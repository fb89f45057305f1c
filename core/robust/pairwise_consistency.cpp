#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <tessera/robust/pairwise_consistency.hpp>

namespace tessera {
namespace {

Pose compose(const Pose& a, const Pose& b) {
  return {a.R * b.R, a.R * b.t + a.t};
}
Pose inverse(const Pose& a) {
  return {a.R.transpose(), -(a.R.transpose() * a.t)};
}

// Cumulative odometry noise along the id chain, so the chain between any two poses costs
// O(1): prefix sums of each known-inlier link's rotation and translation variance.
struct ChainNoise {
  std::vector<double> rotation, translation;  // prefix sums over links (k, k + 1)
  ChainNoise(const PoseGraph& graph, const std::vector<bool>& known) {
    const std::size_t n = graph.num_poses;
    std::vector<double> vr(n, 0.0), vt(n, 0.0);
    for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
      const Measurement& m = graph.measurements[e];
      if (!known[e] || std::max(m.i, m.j) != std::min(m.i, m.j) + 1) continue;
      vr[std::min(m.i, m.j)] = 1.0 / (2.0 * m.kappa);
      vt[std::min(m.i, m.j)] = 1.0 / m.tau;
    }
    rotation.assign(n + 1, 0.0);
    translation.assign(n + 1, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      rotation[k + 1] = rotation[k] + vr[k];
      translation[k + 1] = translation[k] + vt[k];
    }
  }
  double rot(std::size_t a, std::size_t b) const {
    return std::abs(rotation[std::max(a, b)] - rotation[std::min(a, b)]);
  }
  double trans(std::size_t a, std::size_t b) const {
    return std::abs(translation[std::max(a, b)] - translation[std::min(a, b)]);
  }
};

}  // namespace

PairwiseConsistencyResult pairwise_consistency(const PoseGraph& graph,
                                               const std::vector<bool>& known,
                                               const std::vector<Pose>& chain, double c2) {
  if (known.size() != graph.num_measurements() || chain.size() != graph.num_poses)
    throw std::invalid_argument("pairwise_consistency: one flag per measurement, one pose each");
  PairwiseConsistencyResult out;
  for (std::size_t e = 0; e < known.size(); ++e)
    if (!known[e]) out.candidates.push_back(e);
  const std::size_t m = out.candidates.size();
  const ChainNoise noise(graph, known);
  std::vector<std::vector<char>> adjacent(m, std::vector<char>(m, 0));
  std::vector<std::size_t> degree(m, 0);
  for (std::size_t a = 0; a < m; ++a) {
    const Measurement& A = graph.measurements[out.candidates[a]];
    const Pose za{A.R, A.t};
    for (std::size_t b = a + 1; b < m; ++b) {
      const Measurement& B = graph.measurements[out.candidates[b]];
      // x_iA -(A)-> x_jA -(odometry)-> x_jB -(B^-1)-> x_iB -(odometry)-> x_iA
      const Pose forward = compose(inverse(chain[A.j]), chain[B.j]);
      const Pose back = compose(inverse(chain[B.i]), chain[A.i]);
      const Pose cycle = compose(compose(compose(za, forward), inverse(Pose{B.R, B.t})), back);
      const double var_r =
          1.0 / (2.0 * A.kappa) + 1.0 / (2.0 * B.kappa) + noise.rot(A.j, B.j) + noise.rot(B.i, A.i);
      const double lever = forward.t.norm() + back.t.norm() + A.t.norm() + B.t.norm();
      const double var_t = 1.0 / A.tau + 1.0 / B.tau + noise.trans(A.j, B.j) +
                           noise.trans(B.i, A.i) + var_r * lever * lever;
      const int d = graph.d;
      const double r2 = (cycle.R - Eigen::MatrixXd::Identity(d, d)).squaredNorm() / (2.0 * var_r) +
                        cycle.t.squaredNorm() / var_t;
      if (r2 <= c2) {
        adjacent[a][b] = adjacent[b][a] = 1;
        ++degree[a];
        ++degree[b];
        ++out.consistent_pairs;
      }
    }
  }
  // Greedy clique from every candidate, neighbours by falling degree: a heuristic for the
  // maximum clique (exact search is exponential); ties go to the lower index, so the result
  // does not depend on anything but the input.
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return degree[x] > degree[y]; });
  std::vector<std::size_t> best, clique;
  for (std::size_t seed : order) {
    if (degree[seed] + 1 <= best.size()) break;  // cannot beat the best any more
    clique.assign(1, seed);
    for (std::size_t v : order)
      if (v != seed && adjacent[seed][v] &&
          std::all_of(clique.begin(), clique.end(), [&](std::size_t u) { return adjacent[u][v]; }))
        clique.push_back(v);
    if (clique.size() > best.size()) best = clique;
  }
  std::vector<char> kept(m, 0);
  for (std::size_t v : best) kept[v] = 1;
  for (std::size_t a = 0; a < m; ++a)
    if (!kept[a]) out.inconsistent.push_back(out.candidates[a]);
  return out;
}

}  // namespace tessera
