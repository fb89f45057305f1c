#pragma once
// Exact solves with the translation Laplacian by substructuring, for the Newton refinement's
// trial points (newton_refine.cpp): with a trial point's rotations fixed, f is quadratic in the
// translations with Hessian 2 L, L the weighted translation Laplacian (the t-t entries of Q),
// so the translations that minimise f at those rotations are one linear solve away from the
// retracted ones: 2 L x = r, r = -(the translation columns of the Euclidean gradient).
//
// L does not depend on the point, so it is factored once per refinement. As in
// interface_solve.hpp (the Hessian's substructuring) L couples two blocks only through the cut
// measurements, which join interface poses: each block orders its interior first (AMD) and its
// interface last and factors its own block, L_BB = L D L^T (cut measurements on the diagonal).
// With y = L^-1 b (b: the block's rows of the right-hand side, k columns, one per row of the
// lifted iterate):
//   Sigma u = rhat,  Sigma = blockdiag_b(L_GG D_G L_GG^T) + (the cut's coupling entries),
//   rhat_b = L_GG y_G,   x_b = L^-T [D_I^-1 y_I ; L_GG^T u_b]  (= L^-1 b).
// Sigma has one row per interface pose of the team (ais2klinik at N = 5: 34), so every agent
// holds and factors it once; each solve then costs one all-agent sum (the blocks' rhat, mG x k
// numbers each). The interface rows of x are u itself, so every agent knows the neighbours'
// new public translations without another exchange, to the bit (back() writes u into them).
//
// Sigma is singular along the constants (a global translation leaves f unchanged) and nowhere
// else on a connected graph: the team's first interface pose is held fixed (its row and column
// dropped) and the rest factored exactly; where that fails (a disconnected graph) Sigma + eta I
// with eta = 1e-10 of its largest diagonal entry. A block whose own L_BB is not positive
// definite (a piece of it without a cut measurement) reports so, and the caller falls back.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <memory>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/problem/block_problem.hpp>
#include <vector>

namespace tessera {

/// Interface poses of the team (poses with a cut measurement): the size of the translation
/// Sigma, known from the layout alone, so every agent computes the same.
Eigen::Index interface_pose_count(const BlockLayout& layout);

class TranslationInterfaceSolve {
 public:
  /// L(own, other) of one cut measurement: `own` a pose of the block, `other` a neighbour's
  /// (global ids).
  struct Coupling {
    std::size_t own = 0, other = 0;
    double value = 0.0;
  };

  /// `problem`: agent `id`'s block; `layout`: the team's. Orders and factors L_BB.
  TranslationInterfaceSolve(const BlockProblem& problem, const BlockLayout& layout, int id);
  /// The same from the Laplacian itself (the distributed rounding, which has the measurements
  /// but no BlockProblem): `owned` the block's poses (global ids, its order), `entries` L_BB's
  /// (indices into `owned`, both triangles, duplicates add, cut measurements on the diagonal),
  /// `cut` one coupling per cut measurement (duplicates add). A coupling between poses outside
  /// the layout's interface makes share() say the block is unusable (flag 0).
  TranslationInterfaceSolve(const std::vector<std::size_t>& owned,
                            const std::vector<Eigen::Triplet<double>>& entries,
                            const std::vector<Coupling>& cut, const BlockLayout& layout, int id);
  ~TranslationInterfaceSolve();
  TranslationInterfaceSolve(const TranslationInterfaceSolve&) = delete;
  TranslationInterfaceSolve& operator=(const TranslationInterfaceSolve&) = delete;

  /// Interface poses of the team (Sigma's size); this block's first one and its count; block b's.
  Eigen::Index team_size() const;
  Eigen::Index offset() const;
  Eigen::Index size() const;
  Eigen::Index block_offset(int b) const;
  Eigen::Index block_size(int b) const;
  /// Row of `pose` (a global id) in the team's interface, -1 where it is no interface pose.
  Eigen::Index team_row(std::size_t pose) const;

  /// This block's share of Sigma as message values: flag (1 = L_BB positive definite, 0 = not:
  /// nothing follows), the Schur complement's lower triangle (column-major), the count of cut
  /// couplings this block reports (those whose own pose has the smaller id), then (own pose,
  /// neighbour pose, value) for each.
  std::vector<double> share() const;
  /// Every block's share() in id order: assembles and factors Sigma. False (the solve unusable)
  /// when a block's flag is 0 or Sigma cannot be factored. With `factor` false only the shares
  /// are read and checked (false when a block's flag is 0): an agent that receives u from the
  /// one agent that factors Sigma needs no factor of its own (ready() stays false).
  bool assemble(const std::vector<const std::vector<double>*>& blocks, bool factor = true);
  /// True after an assemble() that succeeded.
  bool ready() const;

  /// y = L^-1 P b for the block's rows b (owned poses x k, the owned order).
  void forward(const Eigen::MatrixXd& b, Eigen::MatrixXd& y) const;
  /// The block's rhat = L_GG y_G (its interface poses x k).
  Eigen::MatrixXd interface_residual(const Eigen::MatrixXd& y) const;
  /// u = Sigma^-1 rhat (team_size() x k; rhat: the team's, blocks in id order).
  Eigen::MatrixXd solve_interface(const Eigen::MatrixXd& rhat) const;
  /// x = L^-1 b on the own poses (owned order, k columns) from forward()'s y and the team's u;
  /// its interface poses' rows are u's rows, bit for bit.
  Eigen::MatrixXd back(const Eigen::MatrixXd& y, const Eigen::MatrixXd& u) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;

  // Both constructors: orders and factors L_BB from its entries; keeps the couplings whose own
  // pose has the smaller id.
  void set_up(const std::vector<std::size_t>& owned,
              const std::vector<Eigen::Triplet<double>>& entries, const std::vector<Coupling>& cut,
              const BlockLayout& layout, int id);
};

}  // namespace tessera
