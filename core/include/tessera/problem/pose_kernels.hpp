#pragma once
// Hot kernels of the block objective's derivatives on r x (d+1)n lifted-pose matrices.
// With Eigen's dynamic-size expressions, `2.0 * (X * Q)` (dense r x N times sparse N x N)
// walks the sparse matrix through a transposed row-major view and builds two temporaries per
// call; it was the top entry of the distributed solver's profile. Here each output column is
// accumulated into one contiguous r-vector (X is column-major, so a column is one pose row
// slice), with the row count a template parameter for the ranks that occur (2..6), and the
// Hessian's tangent projection and curvature term are applied pose by pose in one pass.

#include <Eigen/Core>
#include <tessera/problem/data_matrix.hpp>

namespace tessera {

/// out = scale * X * Q for any column-major sparse Q (X: r x N, Q: N x M, out: r x M; out is
/// resized). Same value as Eigen's product up to the order of the additions.
void scaled_dense_times_sparse(const Eigen::MatrixXd& X, const SparseMatrix& Q, double scale,
                               Eigen::MatrixXd& out);

/// In place, on every pose i of the lifted manifold (St(r,d) x R^r)^n at X:
///   H_i <- H_i - X_i sym(X_i^T H_i) - V_i sym(X_i^T G_i)   on the d Stiefel columns,
/// translations unchanged. With H = 2 V Q on entry, this is the Riemannian Hessian of the
/// block objective applied to the tangent vector V (G = Euclidean gradient at X), i.e.
/// Proj_X(H) - Weingarten(X, G, V) of manifold/lifted_manifold.hpp, in one pass.
void apply_hessian_projection(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G,
                              const Eigen::MatrixXd& V, int d, Eigen::MatrixXd& H);

}  // namespace tessera
