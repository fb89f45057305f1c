#pragma once
// Coarse correction (the two-level idea of domain decomposition): block updates move
// information across one block boundary per round, so the slowest error is a smooth drift of
// whole blocks against each other, and rounds grow with the number of blocks. Every scheduled
// round, each block b may additionally move rigidly, X_i -> [G_b Y_i | G_b p_i + c_b] for all
// its poses i, with G_b in O(r) and c_b in R^r. Measurements inside a block do not change
// under such a move, so the coarse problem only sees the cut: for a cut edge (i in a, j in b)
//   kappa ||G_b Y_j - G_a Y_i R_ij||^2 + tau ||G_b p_j + c_b - G_a p_i - c_a - G_a Y_i t_ij||^2
//     = ||Z_b A_ij - Z_a B_ij||_F^2,   Z_b = [G_b c_b]  (r x (r+1)),
// with A_ij = [sqrt(kappa) [Y_j; 0], sqrt(tau) [p_j; 1]], B_ij the same for the transported
// pose i. Summed over the cut this is tr(Z Q_c Z^T) with Q_c an N(r+1) x N(r+1) matrix whose
// (a, b) block is non-zero only for adjacent blocks: one small pose-graph-like problem over N
// rigid motions. Each agent contributes its cut edges' sums ((r+1)^2 numbers per neighbour and
// matrix); one agent gathers them, solves the small problem and sends each agent the motions
// it needs (coarse_exchange.hpp; or, CoarseOptions::gather off, the terms ride in the status
// every agent broadcasts and every agent solves the same problem in the same order), so all
// agents apply bit-identical motions without a coordinator. The motions keep every pose on the
// manifold (G orthogonal), so the iterate stays feasible and the certificate is unaffected;
// a motion is applied only when it lowers f, by exactly the coarse cost's decrease.

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera {

/// The coarse space of the two-level rounds.
///   kBlocks    one rigid motion per block: the coarse problem sees only the cut.
///   kSmoothed  a few rigid motions per block (BFS aggregates of the block's own graph), blended
///              smoothly across aggregate and block borders (smoothed aggregation,
///              coarse_space.hpp): the slow error of a pose graph is smooth bending, which a
///              piecewise-rigid space represents only with a kink at every border.
enum class CoarseSpaceKind { kBlocks, kSmoothed };

/// "blocks", "smoothed".
const char* coarse_space_name(CoarseSpaceKind kind);
/// Inverse of coarse_space_name; throws InputError listing the valid names.
CoarseSpaceKind parse_coarse_space(const std::string& name);

struct CoarseOptions {
  /// Apply the coarse correction (off: the plain one-level round).
  bool enabled = false;
  /// The coarse space (kBlocks: one rigid motion per block).
  CoarseSpaceKind space = CoarseSpaceKind::kBlocks;
  /// kSmoothed: aggregates grown per block (>= 1; a block whose own graph falls apart gets
  /// one more per extra piece).
  int aggregates = 4;
  /// kSmoothed: > 0 scales each block's pieces with its size, one piece per this many of its
  /// poses (rounded), at least 1 and at most `aggregates` (block_aggregates()); 0: `aggregates`
  /// pieces in every block. Why: a group's coarse matrix has a rigid motion per piece, and its
  /// dense products in every CG iteration of the Newton steps cost more than small blocks' own
  /// Hessian products (docs/online.md, "Pieces per block"). >= 0.
  int poses_per_aggregate = 0;
  /// kSmoothed: Jacobi smoothing steps of the aggregates' indicator functions over the whole
  /// graph (0..8; 0 = piecewise rigid). Each step widens every blend by one measurement hop.
  int smoothing_steps = 1;
  /// kSmoothed: the damping omega of a smoothing step w <- (1 - omega) w + omega D^-1 A w, in
  /// (0, 1].
  double smoothing_weight = 2.0 / 3.0;
  /// Rounds between corrections (>= 1): a correction at every round k with k % every == 0.
  /// Only those rounds carry coarse terms.
  int every = 1;
  /// Most Levenberg-Marquardt iterations of one coarse solve (>= 1).
  int max_iterations = 10;
  /// A coarse solve stops when an accepted step lowers the coarse cost by less than this
  /// fraction of it (in [0, 1)).
  double rel_tol = 1e-4;
  /// A solved correction is applied only when it lowers f by at least this fraction of what
  /// the last round's block updates did (>= 0; 0 = whenever it lowers f). When the blocks are
  /// already aligned (few blocks), a tiny correction only disturbs the momentum.
  double min_gain = 0.0;
  /// How terms and motions travel (coarse_exchange.hpp). true: every agent sends its terms to
  /// one solver agent, which solves once and sends each agent only the motions it moves by
  /// (bytes a round grow with N; one more message step on correction rounds). false: the terms
  /// ride in the status every agent broadcasts and every agent solves the same problem (no
  /// extra step; bytes grow with N^2, N solves). Bit-identical iterates either way.
  bool gather = true;

  /// Throws InputError naming the first invalid field.
  void validate() const;
  /// Whether round `round` is a correction round.
  bool scheduled(int round) const { return enabled && round % every == 0; }
};

/// The pieces the smoothed space grows in a block of `block_poses` poses (before a part of the
/// block that falls apart adds its own): `options.aggregates`, or with
/// `options.poses_per_aggregate` > 0 one piece per that many poses, rounded, in
/// [1, options.aggregates].
int block_aggregates(const CoarseOptions& options, std::size_t block_poses);

/// One agent's cut edges, and the coarse terms they give at a point: its own diagonal block of
/// Q_c and the off-diagonal blocks to its higher-numbered neighbours (each block of Q_c is
/// computed by exactly one agent), on the rows its poses use.
class CoarseTerms {
 public:
  /// `owned` and `neighbours`: the block's poses and neighbour poses in the orders of its own
  /// block and of its neighbour copies (BlockProblem::owned(), neighbors()).
  CoarseTerms(int id, int d, const BlockLayout& layout, const std::vector<std::size_t>& owned,
              const std::vector<std::size_t>& neighbours,
              const std::vector<Measurement>& measurements);

  /// The terms at own poses X (r x (d+1)m) and neighbour copies Xn. Layout: a bit mask of the
  /// rows k < r that X or Xn use (rows of a rank-d start stay zero, so their entries are exact
  /// zeros and are not sent); with I = those rows and row r (s = |I|), the upper triangle of
  /// Q_aa on I (column by column), then for each adjacent block b > id (layout.adjacent order)
  /// Q_ab on I x I, column-major.
  std::vector<double> compute(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn) const;

 private:
  struct Edge {
    std::size_t own_slot, neighbour_slot;
    bool own_is_source;  // the measurement goes from the own pose to the neighbour's
    int upper;           // index among the adjacent blocks > id, or -1 (the neighbour sends)
    Eigen::MatrixXd R;
    Eigen::VectorXd t;
    double kappa, tau;
  };
  int d_;
  int num_upper_;
  std::vector<Edge> edges_;
};

struct CoarseResult {
  /// Per block, [G_b c_b] (r x (r+1)); [I 0] when nothing was applied.
  std::vector<Eigen::MatrixXd> motions;
  /// The coarse cost (the cut's part of f) before and after; after <= before.
  double cost_before = 0.0;
  double cost_after = 0.0;
  int iterations = 0;  ///< Levenberg-Marquardt iterations tried.
  bool moved = false;  ///< At least one step was accepted.
};

/// Solves the coarse problem from every agent's terms (terms[a] from agent a's
/// CoarseTerms::compute, in agent-id order). Deterministic: the same input gives bit-identical
/// motions on every agent. Throws std::runtime_error when a term vector has the wrong size.
CoarseResult solve_coarse(const BlockLayout& layout, int r,
                          const std::vector<const std::vector<double>*>& terms,
                          const CoarseOptions& options);

/// Applies the rigid motion Z = [G c] to every pose of X (r x (d+1)m): Y_i -> G Y_i,
/// p_i -> G p_i + c. `first`/`count` select poses (count < 0: to the end).
void apply_motion(const Eigen::MatrixXd& Z, int d, Eigen::MatrixXd& X, Eigen::Index first = 0,
                  Eigen::Index count = -1);

}  // namespace tessera
