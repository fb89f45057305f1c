#pragma once
// The distributed certificate's block-Jacobi factor: an agent's diagonal block of S + shift I
// (S_BB = Q_BB - Lambda_B, d + 1 coordinates a pose), factored once and solved against once per
// LOBPCG iteration with one right-hand side.
//
// How: ordered at the pose level (CHOLMOD's AMD on the m x m pattern of Q_BB's pose blocks, each
// pose's d + 1 coordinates kept together: (d+1)^2 times less work than AMD on the matrix itself),
// factored supernodally (BLAS kernels on the supernodes) and converted to simplicial LDL^T, whose
// solve with one right-hand side avoids the supernodal solve's BLAS calls on small supernodes and
// goes through LdlChainSolve (solvers/ldl_chain_solve.hpp: CHOLMOD's LDL^T solve, ~0.6x its
// instructions; CHOLMOD's LL^T solve has no such copy). Same operator as any Cholesky factor of
// the matrix, up to round-off.

#include <cholmod.h>

#include <tessera/problem/data_matrix.hpp>
#include <vector>

#include "solvers/ldl_chain_solve.hpp"

namespace tessera {

class ShiftedBlockFactor {
 public:
  /// Analyses the pattern of `S` (square, (d+1) m coordinates, pose blocks of `width`; the
  /// lower triangle is read). Throws std::runtime_error when CHOLMOD's analysis fails.
  ShiftedBlockFactor(const SparseMatrix& S, int width);
  ~ShiftedBlockFactor();
  ShiftedBlockFactor(const ShiftedBlockFactor&) = delete;
  ShiftedBlockFactor& operator=(const ShiftedBlockFactor&) = delete;

  /// Factors S + shift I (S: the analysed pattern). False when it is not positive definite.
  bool factor(const SparseMatrix& S, double shift);
  /// r (one row) times (S + shift I)^{-1}, with the last successful factor.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& r);

 private:
  cholmod_common c_;
  cholmod_factor* L_ = nullptr;
  cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;  // solve workspace, reused
  LdlChainSolve chain_;                                       // indexed after every factorization
};

}  // namespace tessera
