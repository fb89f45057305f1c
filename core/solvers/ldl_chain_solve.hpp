#pragma once
// A x = b with a CHOLMOD simplicial LDL^T factor (P A P^T = L D L^T), computing exactly what
// cholmod_solve2(CHOLMOD_A) computes for one right-hand side, with fewer instructions.
//
// Why: the tangent preconditioner's solves are a large part of an IRBCD round, and CHOLMOD's
// simplicial solve loads a row index for every entry it touches. With a pose-contiguous
// ordering the factor's below-diagonal rows come in runs of consecutive indices (a pose's p
// coordinates), so the row pattern is stored once per run here, and a run's updates are
// contiguous (the compiler vectorises the forward substitution's).
//
// How it stays bit-identical: CHOLMOD walks the columns in chains of up to three columns whose
// patterns nest (its own test on the column counts and first off-diagonal rows), and evaluates
// each chain's row update as one expression. build() finds the same chains (forward and
// backward differ: their tests differ) and the solve evaluates the same expressions in the same
// order, reading the values from the factor itself (no copy of L).
//
// Optionally (set_split_dots) the backward dots are summed as four partial sums instead: no
// longer CHOLMOD's bits (the same solve up to round-off), but the sums are no longer one
// dependency chain of subtractions, which is what limits the backward pass's speed.

#include <Eigen/CholmodSupport>
#include <vector>

namespace tessera {

class LdlChainSolve {
 public:
  /// Indexes the runs of `L` (a simplicial LDL^T factor, int indices). False (and nothing
  /// held) for any other factor; the caller then solves with CHOLMOD. Call again after every
  /// numeric factorization (the column layout may change).
  bool build(const cholmod_factor* L);
  /// Backward dots as four partial sums (lane l takes each run's rows k = l mod 4, summed
  /// (l0 + l2) + (l1 + l3) at the end) instead of CHOLMOD's sequential sum. Off by default
  /// (CHOLMOD's bits). Both kernel sets (AVX, SSE2) compute the same lanes, so the same bits.
  void set_split_dots(bool split) { split_dots_ = split; }
  bool split_dots() const { return split_dots_; }
  /// True when build() succeeded.
  bool ready() const { return ready_; }
  void clear();

  /// A x = b: b in `rhs` (original order), x written to `out` (original order). `L` is the
  /// factor build() indexed.
  void solve(const cholmod_factor* L, const double* rhs, double* out) const;

  /// Rows row .. row + length - 1 of a chain's pattern.
  struct Run {
    int row;
    int length;
  };

 private:
  struct Chain {
    int column;  // forward: the chain's first column; backward: its last
    int width;   // 1, 2 or 3
    int run_begin, run_end;
  };
  static void add_runs(const int* rows, int count, std::vector<Run>& runs);
  // The forward and backward substitutions on X (permuted order), with one kernel set.
  template <class Kernels, bool Split>
  void solve_chains(const cholmod_factor* L, double* X) const;
  void solve_chains_sse2(const cholmod_factor* L, double* X) const;
  void solve_chains_sse2_split(const cholmod_factor* L, double* X) const;
  void solve_chains_avx(const cholmod_factor* L, double* X) const;
  void solve_chains_avx_split(const cholmod_factor* L, double* X) const;

  std::vector<Chain> forward_, backward_;
  std::vector<Run> forward_runs_, backward_runs_;
  mutable std::vector<double> y_;
  bool ready_ = false;
  bool split_dots_ = false;
};

}  // namespace tessera
