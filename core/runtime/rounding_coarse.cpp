#include "runtime/rounding_coarse.hpp"

#include <algorithm>

namespace tessera::agent {

RoundingCoarse::RoundingCoarse(const Eigen::SparseMatrix<double>& L_own,
                               const Eigen::SparseMatrix<double>& L_nb,
                               const std::vector<std::uint32_t>& nb_block,
                               const std::vector<bool>& free_row, std::uint32_t self,
                               std::uint32_t blocks)
    : self_(self), free_row_(free_row) {
  // (L Z)_ik = sum of L_ij over block k's poses j: the own columns all fall in column self,
  // each neighbour column in its block's (the anchor's row and column of L are empty).
  std::vector<Eigen::Triplet<double>> trip;
  for (Eigen::Index c = 0; c < L_own.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L_own, c); it; ++it)
      trip.emplace_back(it.row(), static_cast<Eigen::Index>(self), it.value());
  for (Eigen::Index c = 0; c < L_nb.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L_nb, c); it; ++it)
      trip.emplace_back(it.row(), static_cast<Eigen::Index>(nb_block[static_cast<std::size_t>(c)]),
                        it.value());
  AZ_.resize(L_own.rows(), static_cast<Eigen::Index>(blocks));
  AZ_.setFromTriplets(trip.begin(), trip.end());
  touched_.push_back(self);
  for (std::uint32_t b : nb_block) touched_.push_back(b);
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
}

Eigen::VectorXd RoundingCoarse::own_row() const {
  Eigen::VectorXd ones = Eigen::VectorXd::Zero(AZ_.rows());
  for (Eigen::Index s = 0; s < ones.size(); ++s)
    if (free_row_[static_cast<std::size_t>(s)]) ones(s) = 1.0;
  return AZ_.transpose() * ones;
}

bool RoundingCoarse::factorise(Eigen::MatrixXd E) {
  E = 0.5 * (E + E.transpose()).eval();  // the two halves were summed in different orders
  for (Eigen::Index k = 0; k < E.rows(); ++k)
    if (E.row(k).cwiseAbs().maxCoeff() == 0.0) E(k, k) = 1.0;
  E_ = E;
  // A non-finite sum (a NaN from a peer) passes Eigen's LLT (NaN <= 0 is false): refused
  // here, so the rounding goes on without the coarse correction rather than with NaNs.
  if (!E_.allFinite()) return false;
  llt_.compute(E_);
  return llt_.info() == Eigen::Success;
}

Eigen::RowVectorXd RoundingCoarse::block_sum(const Eigen::MatrixXd& v) const {
  Eigen::RowVectorXd s = Eigen::RowVectorXd::Zero(v.cols());
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    if (free_row_[static_cast<std::size_t>(i)]) s += v.row(i);
  return s;
}

void RoundingCoarse::add_offset(Eigen::MatrixXd& v, const Eigen::MatrixXd& y) const {
  const Eigen::RowVectorXd shift = y.row(static_cast<Eigen::Index>(self_));
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    if (free_row_[static_cast<std::size_t>(i)]) v.row(i) += shift;
}

}  // namespace tessera::agent
