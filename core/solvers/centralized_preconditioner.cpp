#include "solvers/centralized_preconditioner.hpp"

#include <stdexcept>
#include <utility>

namespace tessera {

CentralizedPreconditioner::CentralizedPreconditioner(std::unique_ptr<TangentPreconditioner> tangent,
                                                     EuclideanBuilder euclidean,
                                                     double refresh_ratio)
    : tangent_(std::move(tangent)),
      build_euclidean_(std::move(euclidean)),
      refresh_ratio_(refresh_ratio) {
  if (!build_euclidean_)
    throw std::invalid_argument("CentralizedPreconditioner: no Euclidean factor builder");
  if (!(refresh_ratio_ >= 0))
    throw std::invalid_argument("CentralizedPreconditioner: refresh_ratio must be >= 0");
}

CentralizedPreconditioner::~CentralizedPreconditioner() = default;

bool CentralizedPreconditioner::tangent_usable() const {
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

Eigen::MatrixXd CentralizedPreconditioner::apply(const LiftedManifold& manifold,
                                                 const Eigen::MatrixXd& X,
                                                 const Eigen::MatrixXd& V) const {
  if (X.rows() != manifold.dim() || !tangent_usable()) return euclidean().apply(manifold, X, V);
  const bool new_point = point_.rows() != X.rows() || point_.cols() != X.cols() || point_ != X;
  if (new_point) {
    point_ = X;
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
