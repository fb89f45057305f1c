#pragma once
// One agent's data: its block's local problem (own poses, every measurement touching them,
// neighbours' poses held fixed), its blocks of the sequences Y (iterates), P (extrapolated
// points) and V (momentum), and its copies of the neighbours' public poses. Pure data and
// local math; the round protocol (round_protocol.hpp) decides when each piece is used.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/protocol/messages.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <vector>

namespace tessera {

/// An agent's contributions to the global reductions at its current Y.
struct LocalStatus {
  double cost_share = 0.0;    ///< Internal edges in full, cut edges half.
  double grad_norm_sq = 0.0;  ///< ||grad_B f||^2: the block's part of ||grad f||^2.
  /// Selection score: sqrt(grad_norm_sq), or with `newton_score` sqrt(<(2Q_BB)^-1 g, g>).
  double block_grad_norm = 0.0;
};

class AgentState {
 public:
  /// `Y0`: the block's initial lifted poses, r x (d+1)m in layout.poses[id] order. The
  /// preconditioners are factored here (set-up): the Q_BB one, and the tangent one at Y0 when
  /// `options` ask for it, Y0 has d active rows and the Q_BB factor is not too large.
  AgentState(int id, int d, const BlockLayout& layout, const std::vector<Measurement>& measurements,
             const Eigen::MatrixXd& Y0, const BlockUpdateOptions& options = {});
  AgentState(const AgentState&) = delete;
  AgentState& operator=(const AgentState&) = delete;

  int id() const { return id_; }
  int rank() const { return static_cast<int>(Y.rows()); }
  const BlockProblem& problem() const { return problem_; }
  LiftedManifold manifold() const { return problem_.manifold(rank()); }

  /// The public poses of `X` (own block, own order) that neighbour block `recipient` needs.
  PoseBlockMessage publish(const Eigen::MatrixXd& X, BlockKind kind, int recipient,
                           std::uint32_t round, std::uint32_t phase) const;
  /// Writes a neighbour's poses into `copy` (neighbour order). Throws std::runtime_error when
  /// the message names a pose that is not a neighbour of this block or has the wrong size.
  void absorb(const PoseBlockMessage& message, Eigen::MatrixXd& copy) const;

  /// Status at (Y, Yn). `newton_score`: the selection score is the preconditioned gradient
  /// norm (greedy_newton selection) instead of the gradient norm.
  LocalStatus status(bool newton_score = false);
  /// Block update from X0 with neighbours at `neighbours`.
  Eigen::MatrixXd update(const Eigen::MatrixXd& X0, const Eigen::MatrixXd& neighbours,
                         const BlockUpdateOptions& options);
  /// This agent's coarse terms at (Y, Yn) (coarse_correction.hpp).
  std::vector<double> coarse_terms() const { return coarse().compute(Y, Yn); }
  /// Moves every block rigidly by motions[b] (coarse_correction.hpp): the own sequences Y and
  /// V by motions[id], the neighbour copies Yn and Vn pose by pose by their owners' motions.
  void apply_coarse(const std::vector<Eigen::MatrixXd>& motions);
  /// Two-level rounds over the smoothed coarse space (coarse_space.hpp) instead of one rigid
  /// motion per block: `space` is the one every agent built; `measurements` (those touching
  /// this block, or the whole graph's) give this agent's edges of the coarse problem.
  void use_coarse_space(std::shared_ptr<const CoarseSpace> space,
                        const std::vector<Measurement>& measurements);
  /// The smoothed coarse space in use, or null (one rigid motion per block).
  const CoarseSpace* coarse_space() const { return space_.get(); }
  /// The pieces of the Newton refinement's coarse preconditioner (newton_refine.hpp,
  /// NewtonRefineOptions::Coarse::kSmoothed), kept apart from the rounds' space: the rounds
  /// switch to smoothed terms when they hold one.
  void use_refine_space(std::shared_ptr<const CoarseSpace> space) {
    refine_space_ = std::move(space);
  }
  const CoarseSpace* refine_space() const { return refine_space_.get(); }
  /// This agent's smoothed coarse terms at (Y, Yn); needs use_coarse_space.
  std::vector<double> smoothed_coarse_terms() const { return smoothed_->compute(Y, Yn); }
  /// Bytes of this agent's smoothed coarse terms (0 without use_coarse_space).
  std::size_t smoothed_coarse_bytes() const { return smoothed_ ? smoothed_->bytes() : 0; }
  /// Moves Y, V and the neighbour copies Yn, Vn by their blended motions (one per aggregate).
  void apply_smoothed_coarse(const std::vector<Eigen::MatrixXd>& motions);
  /// This block's preconditioner applied to a tangent vector G at X (X: the block's point on
  /// its active rows, any rank): the tangent factor when X has d rows and one is held, else the
  /// Q_BB factor. A symmetric positive definite map of the tangent space at X (the Newton
  /// refinement's block-Jacobi preconditioner, newton_refine.hpp).
  Eigen::MatrixXd precondition(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G);
  /// Factors the tangent preconditioner at X (d rows) when this block can have one (built on
  /// first use): precondition() is then exact for Q_BB's part at X. False when it cannot.
  bool refresh_tangent(const Eigen::MatrixXd& X);
  /// As refresh_tangent(X), with the Hessian's multiplier term of each pose (`egrad`: the
  /// block's Euclidean gradient at X, neighbour terms included): the factor is then this block's
  /// diagonal block of the Riemannian Hessian in tangent coordinates where that is positive
  /// definite (TangentPreconditioner::factorize(X, egrad)).
  bool refresh_tangent(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad);
  /// As refresh_tangent, but a block that holds a factor keeps it (computed at an earlier point
  /// or grown: stale, still positive definite); factors only when it holds none.
  bool ensure_tangent(const Eigen::MatrixXd& X);
  /// A block whose factor was grown (extend() kept it, its new poses appended) builds a new one
  /// at X, as a block without a factor would (analysis and factorization of the grown block);
  /// a block whose factor was not grown keeps it. The Newton steps of an online step run their
  /// first CG on the grown factor and call this at the first accepted step's point
  /// (NewtonRefineOptions::refactor_grown_factors). True when a new factor was built.
  bool rebuild_grown_tangent(const Eigen::MatrixXd& X);
  /// Local objective f_B(X) with neighbours at `neighbours`.
  double local_cost(const Eigen::MatrixXd& X, const Eigen::MatrixXd& neighbours);
  /// Totals over this agent's block updates so far (BlockUpdateStats summed): updates,
  /// truncated-CG iterations, updates preconditioned with the tangent factor, and that
  /// factor's numeric factorizations.
  long long block_updates() const { return block_updates_; }
  long long tcg_iterations() const { return tcg_iterations_; }
  long long tangent_updates() const { return tangent_updates_; }
  int tangent_factorizations() const { return tangent_ ? tangent_->factorizations() : 0; }
  /// Numeric tangent factorizations over this state's life (every factor it held, not only the
  /// current one) and their floating-point operations as CHOLMOD's analysis predicts them: a
  /// load-free measure of the preconditioner's cost (the online engine reports it per step).
  long long tangent_factorizations_total() const { return tangent_factorizations_total_; }
  double tangent_factor_flops_total() const { return tangent_factor_flops_total_; }
  /// True when this block's Q_BB factor was predicted too large and the block diagonal is used
  /// instead (BlockPreconditioner::block_diagonal): any factor of a matrix with Q_BB's pattern
  /// (the certificate's S_BB) would be as large.
  bool block_factor_too_large() const { return block_factor_too_large_; }
  /// Frees the Q_BB factor while no update needs it (the certificate factors its own block
  /// meanwhile: without this both are held at once); the next update that needs it computes it
  /// again, the same factor.
  void release_block_factor() { precon_.reset(); }
  /// The block grew in place (an online run's new data): the layout this state was built with
  /// now lists more poses for this block (the old ones first, in the same order) and
  /// `measurements` (the same growing vector, which must outlive this state) has new entries
  /// from `first_new` on. Extends the local problem with them (BlockProblem::extend: the new
  /// data and a pass over the block's own entries, no scan of the whole graph) and starts the
  /// sequences afresh at Y0 (the grown block) with the neighbour copies at zero: call
  /// reset_iterate with the neighbours' poses (problem().neighbors() order) before a solve. The
  /// tangent factor is kept and grown (TangentPreconditioner::grow) while the block has at most
  /// `refactor_growth` times the poses it was factored with more; beyond that, or when growing
  /// fails, it is built again at the next update. The Q_BB factor is built again when an update
  /// needs it. Throws std::invalid_argument when the block lost or reordered poses (build a new
  /// state then).
  void extend(const std::vector<Measurement>& measurements, std::size_t first_new,
              const Eigen::MatrixXd& Y0, double refactor_growth);
  /// Poses of other blocks changed block (an online re-partition) while this block's own poses
  /// and neighbour poses stayed: the layout this state was built with now has other neighbour
  /// owners and adjacency. Drops what was built from them (the coarse terms, built again on
  /// first use from `measurements`, the same growing vector, which must outlive this state; the
  /// smoothed coarse pieces, set again by use_coarse_space). The problem and its factors stay.
  void neighbours_moved(const std::vector<Measurement>& measurements);
  /// Starts the sequences afresh at Y0 (any rank, e.g. r + 1 after a saddle escape) with
  /// neighbours at Yn0 (same rank, neighbour order).
  void reset_iterate(const Eigen::MatrixXd& Y0, const Eigen::MatrixXd& Yn0);

  // The sequences (own block) and neighbour copies; *_prev keep round k while k+1 is tried,
  // so an adaptive restart can go back. Vn mirrors the neighbours' V on their public poses:
  // every momentum operation is pose-wise and driven by global scalars, so each agent can
  // evolve its neighbours' V (and form their P^k) itself instead of receiving P^k.
  Eigen::MatrixXd Y, P, V, Y_prev, V_prev;
  Eigen::MatrixXd Yn, Pn, Vn, Yn_prev;

 private:
  // refresh_tangent's work; `egrad` null: without the multiplier term.
  bool refactor_tangent(const Eigen::MatrixXd& X, const Eigen::MatrixXd* egrad);
  /// Selects the rows to compute on for the point (X, neighbours) and sets problem_'s
  /// neighbour poses to those rows.
  void set_point(const Eigen::MatrixXd& X, const Eigen::MatrixXd& neighbours);
  /// X restricted to rows_ (X itself when every row is active).
  Eigen::MatrixXd active_part(const Eigen::MatrixXd& X) const;

  int id_;
  int d_;
  const BlockLayout& layout_;
  BlockProblem problem_;
  // Built in the constructor; after extend() on first use, from *coarse_source_.
  mutable std::optional<CoarseTerms> coarse_;
  const std::vector<Measurement>* coarse_source_ = nullptr;
  const CoarseTerms& coarse() const;
  std::shared_ptr<const CoarseSpace> space_;
  std::shared_ptr<const CoarseSpace> refine_space_;
  std::optional<SmoothedCoarseTerms> smoothed_;
  /// The Q_BB preconditioner (built in the constructor).
  BlockPreconditioner& euclidean();
  /// Builds and factors the tangent preconditioner at X (rank d) once; false when unusable.
  bool build_tangent(const Eigen::MatrixXd& X, const BlockUpdateOptions& options);

  std::unique_ptr<BlockPreconditioner> precon_;
  std::unique_ptr<TangentPreconditioner> tangent_;
  bool tangent_tried_ = false;
  bool block_factor_too_large_ = false;
  std::size_t max_factor_entries_;  // BlockUpdateOptions::max_factor_entries of the constructor
  long long block_updates_ = 0, tcg_iterations_ = 0, tangent_updates_ = 0;
  long long tangent_factorizations_total_ = 0;
  double tangent_factor_flops_total_ = 0.0;
  /// Adds the factorizations tangent_ did since it had done `before` to the totals.
  void count_tangent_factorizations(int before);
  Eigen::MatrixXd neighbours_set_;  // what problem_ holds, so X_N Q_NB is rebuilt only on change
  // Rows of the current point that are not identically zero, in increasing order. A lifted
  // point [I_d; 0] R (chordal or distributed initialisation) has r - d zero rows, and every
  // step of the algorithms (gradient, tangent projection, Hessian, Q_BB solve, Proj_M) maps
  // zero rows to zero rows, so the local math runs on the active rows only: the same iterates
  // (up to the order of floating-point additions) at d/r of the cost. A saddle escape fills the
  // new row, after which every row is active.
  std::vector<Eigen::Index> rows_;
  std::uint64_t neighbours_version_ = 0;  // bumped whenever problem_'s neighbour poses change
  // The last update's result and ||grad f_B||^2 there: with one block per round the selected
  // block's neighbours do not move before the next status, whose gradient is then this one.
  Eigen::MatrixXd updated_X_;
  double updated_grad_norm_sq_ = -1.0;  // < 0: nothing to reuse
  double updated_cost_share_ = 0.0;     // cost share there
  std::uint64_t updated_version_ = 0;
};

}  // namespace tessera
