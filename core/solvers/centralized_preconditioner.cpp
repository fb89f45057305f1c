#include "solvers/centralized_preconditioner.hpp"

#include <stdexcept>
#include <utility>

namespace tessera {

CentralizedPreconditioner::CentralizedPreconditioner(std::unique_ptr<TangentPreconditioner> tangent,
                                                     EuclideanBuilder euclidean,
                                                     double refresh_ratio, double switch_fraction)
    : tangent_(std::move(tangent)),
      build_euclidean_(std::move(euclidean)),
      refresh_ratio_(refresh_ratio),
      switch_fraction_(switch_fraction) {
  if (!build_euclidean_)
    throw std::invalid_argument("CentralizedPreconditioner: no Euclidean factor builder");
  if (!(refresh_ratio_ >= 0))
    throw std::invalid_argument("CentralizedPreconditioner: refresh_ratio must be >= 0");
  if (!(switch_fraction_ >= 0))
    throw std::invalid_argument("CentralizedPreconditioner: switch_fraction must be >= 0");
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
      switch_fraction_ = 0;  // one attempt: a failed factorization leaves the Euclidean factor
      if (tangent_->factorize(X)) {
        switched_ = true;
        solves_since_factor_ = 1;
        return tangent_->apply(manifold, X, V);
      }
    }
    if (new_point) euclidean_solves_at_point_ = 0;
    Eigen::MatrixXd out = euclidean().apply(manifold, X, V);
    ++euclidean_solves_at_point_;
    ++euclidean_solves_;
    if (switch_fraction_ > 0 && tangent_ && tangent_->usable()) {
      // A solve is a forward and a backward pass over the factor, ~2 flops an entry each, for
      // each of the d active rows.
      const double solve_flops = 4.0 * static_cast<double>(manifold.dim()) *
                                 static_cast<double>(euclidean_->factor_entries());
      switch_pending_ = static_cast<double>(euclidean_solves_at_point_) * solve_flops >=
                        switch_fraction_ * tangent_->factor_flops();
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
