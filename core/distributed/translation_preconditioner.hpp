#pragma once
// Block Jacobi for the translation solve at a Newton refinement's trial points: with the
// rotations fixed, f is quadratic in the translations (Hessian 2 L, L the translation
// Laplacian), and each block's preconditioner is its own block 2 L_BB (its measurements' tau,
// cut ones on the diagonal: Q_BB's translation-translation part), factored once (it does not
// depend on the point). Vectors are in the pose layout (r x (d+1) per pose) with the rotation
// columns zero.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <tessera/problem/block_problem.hpp>

namespace tessera {

class TranslationPreconditioner {
 public:
  /// Factors the block's L_BB. A block with no cut measurement (one agent) has L_BB singular on
  /// the constants: it is shifted by 1e-9 of its largest diagonal entry (at least 1e-9).
  explicit TranslationPreconditioner(const BlockProblem& problem);

  /// z = (2 L_BB)^-1 r on the translation columns, zero elsewhere (z takes r's shape).
  void apply(const Eigen::MatrixXd& r, Eigen::MatrixXd& z);

  /// Zero in every column of v but the poses' translations (the last of each d+1).
  static void keep_translations(int dim, Eigen::MatrixXd& v);

 private:
  int dim_ = 0;
  Eigen::Index poses_ = 0;  // the block's own poses
  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
  Eigen::MatrixXd rt_, zt_;  // apply's translation columns of r and z, kept for their storage
};

}  // namespace tessera
