#pragma once
// Cholesky factor L L^T = A + shift I of a symmetric matrix whose pattern repeats across calls
// (CHOLMOD supernodal): the ordering and the supernodes are computed when the pattern changes,
// each factor() after that is numeric only, and a factor() that finds A + shift I not positive
// definite may be followed by one with a larger shift on the same analysis. Solves keep their
// workspace across calls.
//
// Two orderings: kAmd (CHOLMOD's AMD, postordered; solve() applies the permutation) for a
// plain solve, or kGiven (the caller's order, rows as given, not postordered) for
// substructuring, where the caller orders a block's interior first and its interface last and
// reads the factor's trailing block (trailing_block()) and solves with L and L^T alone.
//
// Why supernodal: the refinement's interface solves (distributed/interface_solve.hpp) factor
// matrices whose factors are mostly dense blocks (an agent's interface columns; the interface
// matrix Sigma, dense Schur complements joined by the cut's couplings); there the BLAS kernels
// on supernodes take a fraction of the instructions of Eigen's simplicial factorizations
// (figures in interface_solve.hpp).

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

class SupernodalFactor {
 public:
  enum class Ordering { kAmd, kGiven };
  explicit SupernodalFactor(Ordering ordering = Ordering::kAmd);
  ~SupernodalFactor();
  SupernodalFactor(const SupernodalFactor&) = delete;
  SupernodalFactor& operator=(const SupernodalFactor&) = delete;

  /// Factors lower + shift I (`lower`: the lower triangle of a symmetric n x n matrix,
  /// compressed columns; explicit zeros count as pattern). True when it is positive definite;
  /// then the solves below apply. Throws std::runtime_error when CHOLMOD fails otherwise (out
  /// of memory), std::invalid_argument on a matrix that is not square and compressed.
  bool factor(const SparseMatrix& lower, double shift = 0.0);
  /// Whether the last factor() succeeded.
  bool ok() const;

  /// x = (lower + shift I)^-1 b (x resized to b's size). Throws std::logic_error without a
  /// positive definite factor.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  /// kGiven only: v = L^-1 v and v = L^-T v in the given order.
  void solve_l(Eigen::VectorXd& v) const;
  void solve_lt(Eigen::VectorXd& v) const;
  /// kGiven only: L's rows and columns >= first, dense (lower triangular).
  Eigen::MatrixXd trailing_block(Eigen::Index first) const;

  /// The numeric factor's values (CHOLMOD's supernodal L->x, each supernode's columns from the
  /// diagonal down), for import_values() on another SupernodalFactor; empty without a positive
  /// definite factor.
  std::vector<double> values() const;
  /// Installs values() of a positive definite factor of a matrix with the pattern this one was
  /// last factored on (the same analysis gives the same supernodes): the solves then give that
  /// factor's results to the bit. False (nothing changed) where this one holds no numeric
  /// factor of that layout (no factor() yet, or another size).
  bool import_values(const double* x, std::size_t count);

  /// Takes `other`'s analysis (ordering, supernodes, pattern; a copy of its factor), so that the
  /// next factor() of a matrix with that pattern is numeric only. No factor until then.
  void adopt_analysis(const SupernodalFactor& other);

  /// Pattern analyses so far: one per distinct pattern in a row of factor() calls.
  int analyses() const;
  /// Entries of L and the factorization's flops, from the last analysis (0 before).
  std::size_t factor_entries() const;
  double factor_flops() const;

 private:
  void solve_system(int system, Eigen::VectorXd& v) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera
