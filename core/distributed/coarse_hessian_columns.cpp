#include "distributed/coarse_hessian_columns.hpp"

namespace tessera {

void CoarseHessianColumns::reset(std::size_t columns) {
  columns_.assign(columns, {});
}

void CoarseHessianColumns::keep(std::size_t c, const Eigen::MatrixXd& hv,
                                const std::vector<Eigen::Index>& slots) {
  Column& col = columns_[c];
  const Eigen::Index w = hv.rows() * (dim_ + 1);
  for (const Eigen::Index s : slots) {
    const Eigen::Map<const Eigen::VectorXd> b(hv.data() + s * w, w);
    if (b.squaredNorm() == 0.0) continue;
    col.slots.push_back(s);
    col.values.insert(col.values.end(), b.data(), b.data() + w);
  }
}

Eigen::VectorXd CoarseHessianColumns::dot(const Eigen::MatrixXd& y) const {
  Eigen::VectorXd out(static_cast<Eigen::Index>(columns_.size()));
  const Eigen::Index w = y.rows() * (dim_ + 1);
  for (std::size_t c = 0; c < columns_.size(); ++c) {
    const Column& col = columns_[c];
    double acc = 0.0;
    for (std::size_t q = 0; q < col.slots.size(); ++q)
      acc +=
          Eigen::Map<const Eigen::VectorXd>(col.values.data() + static_cast<Eigen::Index>(q) * w, w)
              .dot(Eigen::Map<const Eigen::VectorXd>(y.data() + col.slots[q] * w, w));
    out(static_cast<Eigen::Index>(c)) = acc;
  }
  return out;
}

void CoarseHessianColumns::subtract(const Eigen::VectorXd& x, Eigen::MatrixXd& v) const {
  const Eigen::Index w = v.rows() * (dim_ + 1);
  for (std::size_t c = 0; c < columns_.size(); ++c) {
    const Column& col = columns_[c];
    const double a = x(static_cast<Eigen::Index>(c));
    for (std::size_t q = 0; q < col.slots.size(); ++q)
      Eigen::Map<Eigen::VectorXd>(v.data() + col.slots[q] * w, w) -=
          a * Eigen::Map<const Eigen::VectorXd>(
                  col.values.data() + static_cast<Eigen::Index>(q) * w, w);
  }
}

}  // namespace tessera
