#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <deque>
#include <stdexcept>
#include <string>
#include <tessera/online/new_pose_placement.hpp>
#include <vector>

#include "online/new_pose_adjacency.hpp"

namespace tessera {

namespace {

constexpr std::size_t kNone = static_cast<std::size_t>(-1);

}  // namespace

NewPosePlacement place_new_poses(const PoseGraph& graph, Eigen::MatrixXd& X,
                                 std::size_t first_new_pose, std::size_t first_new_measurement) {
  const int d = graph.d;
  const Eigen::Index w = d + 1;
  const Eigen::Index r = X.rows();
  const std::size_t n = graph.num_poses, m = first_new_pose;
  if (r < d || X.cols() != w * static_cast<Eigen::Index>(n) || m > n)
    throw std::invalid_argument("place_new_poses: estimate is " + std::to_string(X.rows()) + " x " +
                                std::to_string(X.cols()) + " for a graph of " + std::to_string(n) +
                                " poses in " + std::to_string(d) + "D");
  NewPosePlacement out;
  if (m == 0 || m == n) return out;
  const std::size_t first = std::min(first_new_measurement, graph.measurements.size());
  // The new poses reachable from an estimated one over the new measurements.
  const std::vector<std::vector<std::size_t>> touching =
      new_pose_adjacency(graph, m, first_new_measurement);
  std::vector<std::size_t> index(n - m, kNone);  // unknown number of each anchored new pose
  std::vector<std::size_t> ids;
  std::deque<std::size_t> queue;
  auto reach = [&](std::size_t k) {
    if (k >= m && index[k - m] == kNone) {
      index[k - m] = ids.size();
      ids.push_back(k);
      queue.push_back(k);
    }
  };
  for (std::size_t e = first; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if (me.i < m) reach(me.j);
    if (me.j < m) reach(me.i);
  }
  while (!queue.empty()) {
    const std::size_t k = queue.front();
    queue.pop_front();
    for (std::size_t e : touching[k - m]) {
      const Measurement& me = graph.measurements[e];
      reach(me.i == k ? me.j : me.i);
    }
  }
  std::vector<std::size_t> edges;
  for (std::size_t e = first; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if ((me.i >= m && index[me.i - m] != kNone) || (me.j >= m && index[me.j - m] != kNone))
      edges.push_back(e);
  }
  // As many measurements as placed poses: a tree, which composition satisfies exactly.
  if (ids.empty() || edges.size() <= ids.size()) return out;
  const Eigen::Index k = static_cast<Eigen::Index>(ids.size());
  auto unknown = [&](std::size_t pose) -> Eigen::Index {
    return pose >= m ? static_cast<Eigen::Index>(index[pose - m]) : -1;
  };
  auto Y = [&](std::size_t pose) { return X.middleCols(w * static_cast<Eigen::Index>(pose), d); };
  auto p = [&](std::size_t pose) { return X.col(w * static_cast<Eigen::Index>(pose) + d); };

  // Rotations: for each new pose a, sum over its measurements of kappa (Y_a - Y_b M_ab) = 0 with
  // M_ab = R_ij when a = j, R_ij^T when a = i; known Y_b go to the right-hand side. In the
  // unknowns' transposes: L [Y_1^T; ...; Y_k^T] = B, L symmetric positive definite (anchored).
  std::vector<Eigen::Triplet<double>> lt;
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(d * k, r);
  for (std::size_t e : edges) {
    const Measurement& me = graph.measurements[e];
    const Eigen::Index a = unknown(me.j), b = unknown(me.i);  // a: j's unknown, b: i's
    // Residual Y_j - Y_i R: for j, kappa (Y_j - Y_i R); for i, kappa (Y_i - Y_j R^T).
    if (a >= 0) {
      for (int c = 0; c < d; ++c) lt.emplace_back(d * a + c, d * a + c, me.kappa);
      if (b >= 0) {
        for (int x = 0; x < d; ++x)
          for (int y = 0; y < d; ++y)  // block (a, b) = -kappa R^T, block (b, a) = -kappa R
            lt.emplace_back(d * a + x, d * b + y, -me.kappa * me.R(y, x));
      } else {
        B.middleRows(d * a, d) += me.kappa * (Y(me.i) * me.R).transpose();
      }
    }
    if (b >= 0) {
      for (int c = 0; c < d; ++c) lt.emplace_back(d * b + c, d * b + c, me.kappa);
      if (a >= 0) {
        for (int x = 0; x < d; ++x)
          for (int y = 0; y < d; ++y) lt.emplace_back(d * b + x, d * a + y, -me.kappa * me.R(x, y));
      } else {
        B.middleRows(d * b, d) += me.kappa * (Y(me.j) * me.R.transpose()).transpose();
      }
    }
  }
  Eigen::SparseMatrix<double> L(d * k, d * k);
  L.setFromTriplets(lt.begin(), lt.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> rotations(L);
  if (rotations.info() != Eigen::Success) return out;
  const Eigen::MatrixXd Yt = rotations.solve(B);
  if (rotations.info() != Eigen::Success || !Yt.allFinite()) return out;
  std::vector<Eigen::MatrixXd> projected(ids.size());
  for (Eigen::Index a = 0; a < k; ++a) {
    // The nearest point of St(d, r): the polar factor U V^T.
    const Eigen::MatrixXd Ya = Yt.middleRows(d * a, d).transpose();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Ya, Eigen::ComputeThinU | Eigen::ComputeThinV);
    if (svd.singularValues().minCoeff() <= 1e-9 * std::max(1.0, svd.singularValues().maxCoeff()))
      return out;  // a rotation the measurements do not pin down: keep the composed start
    projected[static_cast<std::size_t>(a)] = svd.matrixU() * svd.matrixV().transpose();
  }
  // The composed rotations come back if the translations cannot be solved.
  std::vector<Eigen::MatrixXd> composed(ids.size());
  for (Eigen::Index a = 0; a < k; ++a) {
    composed[static_cast<std::size_t>(a)] = Y(ids[static_cast<std::size_t>(a)]);
    Y(ids[static_cast<std::size_t>(a)]) = projected[static_cast<std::size_t>(a)];
  }
  auto undo = [&]() {
    for (Eigen::Index a = 0; a < k; ++a)
      Y(ids[static_cast<std::size_t>(a)]) = composed[static_cast<std::size_t>(a)];
    return out;
  };

  // Translations with those rotations: tau (p_j - p_i - Y_i t_ij), a weighted graph Laplacian.
  std::vector<Eigen::Triplet<double>> tt;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(k, r);
  for (std::size_t e : edges) {
    const Measurement& me = graph.measurements[e];
    const Eigen::Index a = unknown(me.j), b = unknown(me.i);
    const Eigen::VectorXd step = Y(me.i) * me.t;
    if (a >= 0) {
      tt.emplace_back(a, a, me.tau);
      C.row(a) += me.tau * step.transpose();
      if (b >= 0)
        tt.emplace_back(a, b, -me.tau);
      else
        C.row(a) += me.tau * p(me.i).transpose();
    }
    if (b >= 0) {
      tt.emplace_back(b, b, me.tau);
      C.row(b) -= me.tau * step.transpose();
      if (a >= 0)
        tt.emplace_back(b, a, -me.tau);
      else
        C.row(b) += me.tau * p(me.j).transpose();
    }
  }
  Eigen::SparseMatrix<double> T(k, k);
  T.setFromTriplets(tt.begin(), tt.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> translations(T);
  if (translations.info() != Eigen::Success) return undo();
  const Eigen::MatrixXd P = translations.solve(C);
  if (translations.info() != Eigen::Success || !P.allFinite()) return undo();
  for (Eigen::Index a = 0; a < k; ++a) p(ids[static_cast<std::size_t>(a)]) = P.row(a).transpose();
  out.placed = ids.size();
  out.measurements = edges.size();
  return out;
}

}  // namespace tessera
