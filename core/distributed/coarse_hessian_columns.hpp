#pragma once
// The balancing coarse correction's H Phi (distributed/tangent_coarse_space.hpp): an agent's own
// rows of the Hessian applied to the coarse basis, one column per coarse unknown it touches, kept
// only on the poses where the column is non-zero (its piece's support and one hop around it), so
// that the products with H Phi cost about one Hessian product a CG iteration, not one per column.
// Vectors are the block's tangent vectors in the pose layout (rows x (d+1) per pose).

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace tessera {

class CoarseHessianColumns {
 public:
  /// `dim`: d of the poses (d + 1 columns each).
  explicit CoarseHessianColumns(int dim) : dim_(dim) {}

  /// Drops what is kept and makes room for `columns` columns, all zero.
  void reset(std::size_t columns);
  /// Keeps hv = the own rows of H Phi e_u as column c (its non-zero poses only). `slots`
  /// (ascending): the pose slots where hv may be non-zero, the only ones looked at.
  void keep(std::size_t c, const Eigen::MatrixXd& hv, const std::vector<Eigen::Index>& slots);
  std::size_t size() const { return columns_.size(); }

  /// (H Phi)^T y over the own rows, one entry per column.
  Eigen::VectorXd dot(const Eigen::MatrixXd& y) const;
  /// v -= (H Phi) x, x one entry per column.
  void subtract(const Eigen::VectorXd& x, Eigen::MatrixXd& v) const;

 private:
  struct Column {
    std::vector<Eigen::Index> slots;  // pose slots
    std::vector<double> values;       // rows x (d+1) per slot, column-major
  };
  int dim_ = 0;
  std::vector<Column> columns_;
};

}  // namespace tessera
