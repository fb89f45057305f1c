#include "solvers/centralized_preconditioner.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <utility>
#include <vector>

#include "solvers/pose_level_analysis.hpp"

namespace tessera {

TangentFactorEstimate estimate_tangent_factor(const BlockProblem& problem) {
  TangentFactorEstimate out;
  const int d = problem.dim(), w = d + 1, p = d * (d + 1) / 2;
  const Eigen::Index m = static_cast<Eigen::Index>(problem.num_owned());
  if (m == 0) return out;
  const SparseMatrix& Q = problem.data_matrix();
  // The pose-level pattern (lower triangle with the diagonal; CHOLMOD reads the lower half).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(Q.nonZeros() / (w * w) + m));
  for (Eigen::Index j = 0; j < m; ++j) {
    entries.emplace_back(j, j, static_cast<double>(m));
    for (int s = 0; s < w; ++s)
      for (SparseMatrix::InnerIterator it(Q, j * w + s); it; ++it)
        if (it.row() / w > j) entries.emplace_back(it.row() / w, j, 1.0);
  }
  SparseMatrix B(m, m);
  B.setFromTriplets(entries.begin(), entries.end(), [](double a, double) { return a; });
  const PoseLevelAnalysis a = analyse_pose_level_pattern(B, false);
  if (!a.ok) return out;
  const double md = static_cast<double>(m), pd = p;
  out.entries = (a.factor_entries - md) * pd * pd + md * pd * (pd + 1) / 2;
  out.flops = a.flops * pd * pd * pd;
  return out;
}

CentralizedPreconditioner::CentralizedPreconditioner(std::unique_ptr<TangentPreconditioner> tangent,
                                                     EuclideanBuilder euclidean,
                                                     double refresh_ratio, TangentBuilder switch_to,
                                                     double switch_flops)
    : tangent_(std::move(tangent)),
      build_euclidean_(std::move(euclidean)),
      refresh_ratio_(refresh_ratio),
      switch_to_(std::move(switch_to)),
      switch_flops_(switch_flops) {
  if (!build_euclidean_)
    throw std::invalid_argument("CentralizedPreconditioner: no Euclidean factor builder");
  if (!(refresh_ratio_ >= 0))
    throw std::invalid_argument("CentralizedPreconditioner: refresh_ratio must be >= 0");
  if (switch_to_ && !(switch_flops_ > 0))
    throw std::invalid_argument("CentralizedPreconditioner: switch_flops must be > 0");
}

CentralizedPreconditioner::~CentralizedPreconditioner() = default;

bool CentralizedPreconditioner::tangent_in_use() const {
  return tangent_ && tangent_->factored();
}

const BlockPreconditioner& CentralizedPreconditioner::euclidean() const {
  if (!euclidean_) euclidean_ = build_euclidean_();
  return *euclidean_;
}

int CentralizedPreconditioner::tangent_factorizations() const {
  return tangent_ ? tangent_->factorizations() : 0;
}

bool CentralizedPreconditioner::euclidean_built() const {
  return euclidean_ != nullptr;
}

bool CentralizedPreconditioner::switched() const {
  return switched_;
}

long CentralizedPreconditioner::euclidean_solves() const {
  return euclidean_solves_;
}

bool CentralizedPreconditioner::changes_at_next_apply() const {
  return switch_pending_;
}

Eigen::MatrixXd CentralizedPreconditioner::apply(const LiftedManifold& manifold,
                                                 const Eigen::MatrixXd& X,
                                                 const Eigen::MatrixXd& V) const {
  if (X.rows() != manifold.dim()) return euclidean().apply(manifold, X, V);
  const bool new_point = point_.rows() != X.rows() || point_.cols() != X.cols() || point_ != X;
  if (new_point) point_ = X;
  if (!tangent_in_use()) {
    if (switch_pending_) {
      switch_pending_ = false;
      // One attempt: an unusable or failed factor leaves the Euclidean one for good.
      tangent_ = switch_to_();
      switch_to_ = nullptr;
      if (tangent_ && tangent_->usable() && tangent_->factorize(X)) {
        switched_ = true;
        solves_since_factor_ = 1;
        return tangent_->apply(manifold, X, V);
      }
    }
    if (new_point) euclidean_solves_at_point_ = 0;
    Eigen::MatrixXd out = euclidean().apply(manifold, X, V);
    ++euclidean_solves_at_point_;
    ++euclidean_solves_;
    if (switch_to_) {
      // A solve is a forward and a backward pass over the factor, ~2 flops an entry each, for
      // each of the d active rows.
      const double solve_flops = 4.0 * static_cast<double>(manifold.dim()) *
                                 static_cast<double>(euclidean_->factor_entries());
      switch_pending_ =
          static_cast<double>(euclidean_solves_at_point_) * solve_flops >= switch_flops_;
    }
    return out;
  }
  if (new_point) {
    // A solve is a forward and a backward pass over the factor, ~2 flops an entry each.
    const double solve_flops = 4.0 * static_cast<double>(tangent_->factor_entries());
    if (refresh_ratio_ > 0 &&
        solves_since_factor_ * solve_flops >= refresh_ratio_ * tangent_->factor_flops()) {
      // A failed refactorization leaves the factor unusable: the Euclidean one takes over.
      if (!tangent_->factorize(X)) return euclidean().apply(manifold, X, V);
      solves_since_factor_ = 0;
    }
  }
  solves_since_factor_ += 1;
  return tangent_->apply(manifold, X, V);
}

}  // namespace tessera
