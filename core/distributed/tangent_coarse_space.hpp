#pragma once
// The coarse space of the Newton refinement's preconditioner (newton_refine.hpp): infinitesimal
// rigid motions of pieces of the map, as tangent vectors of the lifted problem.
//
// Why: block Jacobi cannot see the slow modes of a long chain, the blocks' motions against each
// other (ais2klinik: the parts north and south of agent 0's corridor turn rigidly by +0.14 and
// -0.19 rad), so each CG iteration moves information across one block boundary only. Each piece
// alpha (a block, or an aggregate of the smoothed space, coarse_space.hpp) gets the generators
// E = [Omega c] of se(k) on the k active rows (Omega skew k x k, c in R^k; k(k-1)/2 + k of
// them); pose i moves by sum_alpha w_i,alpha E_alpha [X_i; 0 1] = [Omega_i Y_i, Omega_i p_i + c_i],
// which is tangent (Y^T Omega Y is skew). Phi is the map from the coarse coordinates xi
// (pieces x generators) to such a tangent vector; the preconditioner adds Phi A^+ Phi^T r, with
// A = Phi^T Hess f Phi the Galerkin matrix (two-level additive Schwarz).
//
// Each agent knows the weights of its own poses and of its copies of its neighbours' poses from
// the space (identical on every agent), so Phi and Phi^T of its rows need no message.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cstddef>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <vector>

namespace tessera {

class TangentCoarseSpace {
 public:
  /// `space`: the pieces and weights (null: one piece per block, weight 1, from the layout).
  /// `owned`, `neighbours`: global ids of the block's poses and neighbour copies (BlockProblem
  /// order); `d`: the poses' dimension; `k`: the rows of the vectors it maps (the refinement's
  /// active rows); `min_group_blocks`: the blocks a group needs to take part (>= 2; groups()).
  TangentCoarseSpace(const CoarseSpace* space, const BlockLayout& layout,
                     const std::vector<std::size_t>& owned,
                     const std::vector<std::size_t>& neighbours, int d, int k,
                     int min_group_blocks = 2);

  /// Generators per piece: k(k-1)/2 rotations then k translations.
  int generators() const { return g_; }
  int pieces() const { return pieces_; }
  /// Coarse unknowns: pieces() x generators(), unknown alpha * generators() + j.
  int size() const { return pieces_ * g_; }
  /// The unknowns whose vectors are non-zero on an own pose or a neighbour copy, ascending:
  /// the columns of A this agent's rows contribute to. Only pieces in a group of two blocks or
  /// more (groups(); `min_group_blocks` or more where the constructor was given that).
  const std::vector<int>& touched() const { return touched_; }
  /// The unknowns non-zero on an own pose, ascending (of linked pieces, as touched()).
  const std::vector<int>& own() const { return own_; }

  /// out += Phi^T v over the own poses (X: the own point, v: a vector of its shape; out has
  /// size() entries), at the linked pieces' unknowns (the others are left as they are).
  void project(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v, double* out) const;
  /// The same over the own pose slots `slots` only (ascending; v zero on the others).
  void project(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v,
               const std::vector<Eigen::Index>& slots, double* out) const;
  /// The own and neighbour slots where `piece` has a weight, ascending.
  std::vector<Eigen::Index> own_slots(int piece) const { return slots_of(own_poses_, piece); }
  std::vector<Eigen::Index> neighbour_slots(int piece) const {
    return slots_of(neighbour_poses_, piece);
  }
  /// v += Phi xi on the own poses (X's shape), xi's entries at own() only.
  void expand(const Eigen::MatrixXd& X, const Eigen::VectorXd& xi, Eigen::MatrixXd& v) const;
  /// The vector of one unknown on the own poses (v) and the neighbour copies (vn), set to the
  /// shapes of X and Xn.
  void unit(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn, int unknown, Eigen::MatrixXd& v,
            Eigen::MatrixXd& vn) const;
  /// The lift of one piece: on its slots (`own`, `neighbour`: own_slots() and neighbour_slots()),
  /// slot s of W (Wn) += w_s [X_s; 0 1], k + 1 rows, w_s the slot's weight of the piece; the
  /// caller keeps W and Wn zero elsewhere. Each of the piece's unknowns' vectors is E W with E =
  /// [Omega c] its generator (k x (k+1)), so a linear map M of them all is E (W M): one product
  /// per piece, not one per generator (apply_generator() reads each off it).
  void lift_on(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn, int piece,
               const std::vector<Eigen::Index>& own, const std::vector<Eigen::Index>& neighbour,
               Eigen::MatrixXd& W, Eigen::MatrixXd& Wn) const;
  /// out = E M for generator j (M: k + 1 rows; out: k rows, M's columns): E's one or two
  /// non-zero entries are +-1, so out's rows are copies of M's rows (with the vectors lift_on()
  /// gives, the same numbers as unit()'s, whose products with E's zeros add only zeros).
  void apply_generator(int j, const Eigen::MatrixXd& M, Eigen::MatrixXd& out) const;

  /// Pieces whose poses are linked by measurements, directly or through other pieces (the
  /// connected components of the layout's block graph; a piece of the smoothed space goes with
  /// its block): group_of(alpha) numbers them densely in order of their first piece.
  int groups() const { return groups_; }
  int group_of(int piece) const { return group_of_piece_[static_cast<std::size_t>(piece)]; }
  /// Some group holds pieces of `min_group_blocks` blocks or more (else the correction is left
  /// out: every motion of a lone piece is gauge, and a lone block's inner pieces are block
  /// Jacobi's work; a group of fewer blocks is left out as a lone block is).
  bool linked() const { return !linked_group_unknowns_.empty(); }

  /// A positive semi-definite inverse of the Galerkin matrix A (size() x size(), symmetric):
  /// the rigid motions of each group of linked pieces (every piece of the group the same
  /// generator: f does not change along them) are projected out, then eigenvalues at or below
  /// `tol` times the largest (generators that move no pose, and any negative curvature, which a
  /// preconditioner must not invert) are dropped. Per group, not only the whole team's motion:
  /// an online graph whose robots have not all met has one gauge per piece of the map, where
  /// A's entries are round-off or of the gradient's order (f is invariant only at a critical
  /// point to second order), which a tolerance relative to the largest eigenvalue does not
  /// catch; their inverses sent CG along directions the retraction does not keep f on.
  /// Computed per group (A is block diagonal over them; the tolerance is relative to each
  /// group's largest eigenvalue). Deterministic: the same A gives the same bits on every agent.
  Eigen::MatrixXd pseudo_inverse(const Eigen::MatrixXd& A, double tol = 1e-10) const;

  /// What an agent's share of A needs to carry: per group of two blocks or more, the upper
  /// triangle of its diagonal block (A is zero between groups and on lone pieces), so a sum
  /// costs sum_g m_g (m_g + 1) / 2 numbers rather than size() (size() + 1) / 2.
  std::size_t packed_size() const;
  /// Appends to `out` the packed_size() numbers of L (size() x size()), symmetrized.
  void pack(const Eigen::MatrixXd& L, std::vector<double>& out) const;
  /// Keeps the summed packed numbers as A, block by block, and A^+ (as pseudo_inverse(), but
  /// from a Cholesky factor of each group's projected block plus its rigid motions, P (B + c U
  /// U^T)^-1 P: n^3 / 3 flops against the eigendecomposition's ~10 n^3, which it falls back to
  /// where that factor fails, has a pivot at or below `tol` times the largest, or its smallest
  /// eigenvalue, estimated by inverse iteration with the factor, is at or below `tol` times the
  /// largest diagonal entry: negative curvature, a generator that moves no pose, or a direction
  /// of nearly no curvature, which pseudo_inverse() drops too).
  void set_matrix(const double* packed, double tol = 1e-10);
  /// The same, but inverting `inverted` (packed as `galerkin`) while times_matrix() keeps
  /// multiplying by `galerkin`: a preconditioner built from another matrix than the Hessian's
  /// Galerkin matrix (NewtonRefineOptions::coarse_multipliers false) whose balancing still
  /// needs Phi^T H Phi.
  void set_matrices(const double* inverted, const double* galerkin, double tol = 1e-10);
  /// A x and A^+ x with the kept A (x and the result: size() entries; zero outside the groups;
  /// with set_matrices(), A x is the Galerkin matrix's and A^+ x the inverted one's).
  Eigen::VectorXd times_matrix(const Eigen::VectorXd& x) const;
  Eigen::VectorXd times_inverse(const Eigen::VectorXd& x) const;

 private:
  struct Weight {
    int piece;
    double w;
  };
  // Pose slot s's pieces: weights[start[s] .. start[s+1]).
  struct Poses {
    std::vector<std::size_t> start;
    std::vector<Weight> weights;
  };
  // The pseudo-inverse of one group's block of A (the group's rigid motions projected out).
  Eigen::MatrixXd group_inverse(const Eigen::MatrixXd& Ag, double tol) const;
  static std::vector<Eigen::Index> slots_of(const Poses& p, int piece);
  // project()'s sums over the given own slots.
  template <class Slots>
  void project_over(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v, const Slots& slots,
                    double* out) const;
  static Poses weights_of(const CoarseSpace* space, const BlockLayout& layout,
                          const std::vector<std::size_t>& ids);
  // [Omega c] of generator j scaled by x, added to E = e[0 .. k(k+1)) column-major k x (k+1).
  void add_generator(int j, double x, double* e) const;
  // v's slot s += E [X_s; 0 1], E = e[0 .. k(k+1)) column-major k x (k+1).
  void move(const double* e, const Eigen::MatrixXd& X, Eigen::Index s, Eigen::MatrixXd& v) const;

  int d_, k_, g_, pieces_;
  int groups_ = 0;
  std::vector<int> group_of_piece_;
  std::vector<char> linked_;               // by piece: in a group with another piece
  std::vector<std::size_t> linked_slots_;  // own slots some linked piece weighs
  // Unknowns (piece * g + generator) of each group of two pieces or more: A's diagonal blocks.
  std::vector<std::vector<Eigen::Index>> linked_group_unknowns_;
  Poses own_poses_, neighbour_poses_;
  std::vector<int> touched_, own_;
  std::vector<std::pair<int, int>> rotation_pairs_;  // (a, b), a < b, for generators 0..
  // set_matrix: per linked group, A's block, and A^+ as a Cholesky factor of B + c U U^T (then
  // projected) or, where that failed, as a dense matrix.
  struct GroupMatrix {
    Eigen::MatrixXd A;
    Eigen::LLT<Eigen::MatrixXd> llt;
    bool dense = false;
    Eigen::MatrixXd inverse;
  };
  std::vector<GroupMatrix> matrices_;
};

/// Whether a Newton step whose coarse matrix was summed `kept_steps` accepted steps ago keeps it
/// (sums only Phi^T g): only the data part's matrix is kept (`data_part`, no multipliers), once
/// one was assembled, for fewer than `keep_steps` steps (NewtonRefineOptions::coarse_keep_steps).
/// The one rule behind the step's coarse sum and the trial sums that carry its Phi^T g ahead.
inline bool keeps_coarse_matrix(bool data_part, int assemblies, int kept_steps, int keep_steps) {
  return data_part && assemblies > 0 && kept_steps < keep_steps;
}

}  // namespace tessera
