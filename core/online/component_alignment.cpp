#include <Eigen/LU>
#include <Eigen/QR>
#include <stdexcept>
#include <string>
#include <tessera/online/component_alignment.hpp>
#include <utility>

namespace tessera {

Eigen::MatrixXd lifted_rotation_between(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  if (A.rows() != B.rows() || A.cols() != B.cols() || A.rows() < A.cols())
    throw std::invalid_argument("lifted_rotation_between: frames of different shapes");
  const Eigen::Index r = A.rows(), d = A.cols();
  if (r == d) return B * A.transpose();
  // Complete each frame to an orthonormal basis of R^r; Q sends one basis to the other.
  auto complete = [r, d](const Eigen::MatrixXd& F) {
    Eigen::MatrixXd U(r, r);
    U.leftCols(d) = F;
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(F);
    U.rightCols(r - d) = (qr.householderQ() * Eigen::MatrixXd::Identity(r, r)).rightCols(r - d);
    return U;
  };
  Eigen::MatrixXd Ub = complete(B);
  const Eigen::MatrixXd Ua = complete(A);
  // det Q = +1: a proper rotation, so the piece keeps its orientation in the lifted space
  // (flipping a completing column leaves Q A = B).
  if (Ub.determinant() * Ua.determinant() < 0) Ub.col(r - 1) *= -1.0;
  return Ub * Ua.transpose();
}

std::size_t ComponentAlignment::root(std::size_t k) {
  while (parent_[k] != k) {
    parent_[k] = parent_[parent_[k]];
    k = parent_[k];
  }
  return k;
}

void ComponentAlignment::grow(std::size_t n) {
  for (std::size_t k = parent_.size(); k < n; ++k) {
    parent_.push_back(k);
    members_.push_back({k});
    ++pieces_;
  }
}

ComponentMerges ComponentAlignment::absorb(const PoseGraph& graph, Eigen::MatrixXd& X, bool align) {
  const int d = graph.d;
  const Eigen::Index w = d + 1;
  if (X.rows() < d || X.cols() != w * static_cast<Eigen::Index>(graph.num_poses) ||
      graph.num_poses < parent_.size() || graph.measurements.size() < seen_measurements_)
    throw std::invalid_argument("ComponentAlignment::absorb: the iterate is " +
                                std::to_string(X.rows()) + " x " + std::to_string(X.cols()) +
                                " for a graph of " + std::to_string(graph.num_poses) +
                                " poses in " + std::to_string(d) + "D");
  grow(graph.num_poses);
  ComponentMerges out;
  auto Y = [&](std::size_t k) { return X.middleCols(w * static_cast<Eigen::Index>(k), d); };
  auto p = [&](std::size_t k) { return X.col(w * static_cast<Eigen::Index>(k) + d); };
  for (std::size_t e = seen_measurements_; e < graph.measurements.size(); ++e) {
    const Measurement& m = graph.measurements[e];
    std::size_t a = root(m.i), b = root(m.j);
    if (a == b) continue;
    // Move the piece of j unless the piece of i is smaller.
    const bool move_i = members_[a].size() < members_[b].size();
    const std::size_t moved = move_i ? a : b, kept = move_i ? b : a;
    // A single pose is no piece yet: it was just placed by composition from this very link
    // (or is a robot's first pose), so there is no frame of its own to reconcile.
    if (align && members_[moved].size() > 1) {
      const std::size_t anchor = move_i ? m.i : m.j;  // the moved piece's pose on the link
      Eigen::MatrixXd target_Y(X.rows(), d);
      Eigen::VectorXd target_p(X.rows());
      if (move_i) {  // R_i = R_j R_ij^T, t_i = t_j - R_i t_ij
        target_Y = Y(m.j) * m.R.transpose();
        target_p = p(m.j) - target_Y * m.t;
      } else {
        target_Y = Y(m.i) * m.R;
        target_p = p(m.i) + Y(m.i) * m.t;
      }
      const Eigen::MatrixXd Q = lifted_rotation_between(Y(anchor), target_Y);
      const Eigen::VectorXd from = p(anchor);
      for (std::size_t k : members_[moved]) {
        Y(k) = (Q * Y(k)).eval();
        p(k) = Q * (p(k) - from) + target_p;
      }
      out.poses_moved += members_[moved].size();
      ++out.merges;
    }
    // The moved piece is never the larger: its list joins the kept one's.
    members_[kept].insert(members_[kept].end(), members_[moved].begin(), members_[moved].end());
    members_[moved].clear();
    members_[moved].shrink_to_fit();
    parent_[moved] = kept;
    --pieces_;
  }
  seen_measurements_ = graph.measurements.size();
  return out;
}

}  // namespace tessera
