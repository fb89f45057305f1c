#pragma once
// The distributed rounding of the final lifted iterate to SE(d), with no central step: core's
// round_solution (rank-d truncation via the r x r Gram matrix summed over the agents,
// reflection by majority, per-block projection to SO(d), translations optimal for those
// rotations with pose 0 at the origin) up to floating-point summation order. The translations
// come from one of two solves:
// - exact, through the team's interface (distributed/translation_interface_solve.hpp) when it
//   has at most DistributedRoundingOptions::interface_max_poses poses: every agent factors its
//   translation Laplacian block and sends its Schur complement with the Gram matrix, then its
//   interface residuals to the agent that factors Sigma and back the interface translations
//   (runtime/rounding_interface.cpp);
// - otherwise (or when a block's Laplacian is singular) a distributed preconditioned conjugate
//   gradient, one message step per iteration, its cost within
//   DistributedRoundingOptions::cost_bound() of the exact solve's.
// Runs after core's protocol in run_round_loop, over the same Mailbox.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/graph/pose.hpp>
#include <vector>

#include "distributed/translation_interface_solve.hpp"
#include "runtime/round_loop.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {

// Phases of the rounding messages (statuses and pose blocks), after core's protocol.
enum RoundingPhase : std::uint32_t {
  kGram = kRoundingPhaseBase,  // r x r Gram matrix of the block's rotation parts
  kNegative,                   // number of rounded blocks with det < 0
  kRotations,                  // rounded rotations of public poses
  kInitialResidual,            // retired: plain PCG's first <r,z>, <r,r>
  kDirection,                  // PCG: public entries of u (first step), then of M w and x
  kCurvature,                  // retired: plain PCG's <p, L p>
  kResidual,                   // pipelined PCG: <r,u>, <w,u>, <r,r> of an iteration
  kTranslations,               // retired: the final translations ride on the last CG step
  kCost,                       // cost share of the rounded poses
  kTraffic,                    // certificate and escape bytes sent (certification only)
  kWarmStartAnchor,            // pose 0's translation in the rounded frame (its owner's)
  kWarmStartValues,            // public entries of the warm start
  kWarmStartNorm,              // |b|^2, with the warm start's step
  kCoarseMatrix,               // a block's row of the coarse matrix E = Z^T L Z
  kCoarseSums,                 // the CG step's sums with the coarse level's terms
  kInterfaceShare,             // the interface solve: a block's Schur share (with the Gram)
  kInterfaceResidual,          // the interface solve: a block's interface residual rhat
  kInterfaceCost,              // the interface solve: cost share and pose 0's translation
  kInterfaceSolution           // the interface solve: u from the agent that factors Sigma
};

/// How the rounding solves for the translations (every agent must use the same).
struct DistributedRoundingOptions {
  /// Start the translation CG from the iterate's own translations (in the rounded frame, pose 0
  /// at the origin) instead of from zero. Near a critical point they are close to the optimal
  /// translations for the rounded rotations, so the CG has little left to do.
  bool warm_start = true;
  /// Also stop the CG once the rounded cost it could still remove, estimated over the last
  /// `settle_window` steps, is at most settle_tolerance * max(1, f(X)); 0 = only the residual
  /// stop (1e-12 of b's). [0, 1e-6]. The window's sum misses a slowly converging tail: on the
  /// paper graphs the rounded cost ended up to 0.92x the target above the exact solve's
  /// (city10000; block Jacobi alone, before the coarse level: 5.6x;
  /// scripts/bench/rounding_iterations.py). The bound that holds with margin,
  /// cost_bound() = 100 settle_tolerance, is at the default 1e-8 of max(1, f(X)), 1e-3 of
  /// the rounding-gap tolerance (certification/rounding_gap.hpp): the inexact solve cannot
  /// decide whether the certificate carries over to the estimate.
  double settle_tolerance = 1e-10;
  /// Steps over which the remaining cost is estimated, [1, 1000].
  std::size_t settle_window = 10;
  /// Add a coarse level to the CG's block-Jacobi preconditioner: one translation offset per
  /// block, its N x N matrix solved by every agent (runtime/rounding_coarse.hpp). Without it
  /// the steps grow with the number of blocks: on a generated 100,000-pose grid after 5
  /// rounds, 83 / 91 / 109 steps to the default stop at N = 16 / 25 / 64, with it 40 / 40 / 37
  /// (scripts/bench/rounding_blocks.py).
  bool coarse_correction = true;
  /// Solve the translations exactly through the team's interface (one share with the Gram
  /// matrix's message, one all-agent sum, instead of the CG's message step per iteration) when
  /// the team has at most this many interface poses (poses with a cut measurement); 0 = the CG
  /// always. [0, 1000000]. Every agent holds the interface matrix Sigma (one row per interface
  /// pose, about as sparse as the cut; its factor: interface_one_factor_min_poses) and receives
  /// every block's dense Schur
  /// complement (nG (nG + 1) / 2 numbers each): the same cap as the Newton refinement's exact
  /// trial translations (NewtonRefineOptions::translation_interface_max_poses).
  std::size_t interface_max_poses = 2000;
  /// From this many interface poses on, only the first agent factors Sigma: the others send it
  /// their interface residuals and receive u (one more delivery, the same bits); below it every
  /// agent factors Sigma and the residuals go to all in one message step. Sigma's factorization
  /// grows about as its size cubed, the extra delivery does not: torus3D's 483-pose Sigma took
  /// 37 M instructions an agent, ais2klinik's 32-pose one little. [0, 1000000].
  std::size_t interface_one_factor_min_poses = 200;

  /// Throws InputError naming the field when it is out of range.
  void validate() const;

  /// How far above the exact solve's cost the rounded cost may end, relative to max(1, f(X)).
  double cost_bound() const { return 100.0 * settle_tolerance; }
};

/// One agent's side of the rounding. It keeps references to its arguments (they must outlive
/// it) and rounds the iterate `state.Y` as it is when run() is called. Throws InputError when
/// `options` are invalid.
class DistributedRounding {
 public:
  DistributedRounding(const AgentLocalData& local, const BlockLayout& layout,
                      const AgentState& state, Mailbox& mail,
                      DistributedRoundingOptions options = {})
      : options_((options.validate(), options)),
        local_(local),
        layout_(layout),
        mail_(mail),
        self_(local.agent_id),
        d_(local.d),
        own_(layout.poses[local.agent_id]),
        Y_(state.Y) {
    for (std::uint32_t a = 0; a < local.num_agents; ++a) everyone_.push_back(a);
    for (int b : layout.adjacent[self_]) neighbours_.push_back(static_cast<std::uint32_t>(b));
  }

  /// A global sum of (a, b) over the agents, in agent-id order (bit-identical on every
  /// agent): returns the sum of a and stores the sum of b in *b_sum when given. Every agent
  /// must call it with the same `phase`, once per phase.
  double sum_over_agents(std::uint32_t phase, double a, double b, double* b_sum) {
    return reduce(phase, 0, a, b, b_sum);
  }

  DistributedRounding(const DistributedRounding&) = delete;
  DistributedRounding& operator=(const DistributedRounding&) = delete;
  ~DistributedRounding();

  /// Rounds this agent's block of the final lifted iterate (every agent calls it together)
  /// and returns `res` with poses (of `owned`, in order), cost (of the rounded poses, whole
  /// graph), translation_iterations (0 for the interface solve) and rounding_interface_poses
  /// (0 for the CG) set. Throws std::runtime_error when a peer's message is missing after the
  /// timeout or malformed.
  RoundLoopResult run(RoundLoopResult res);

 private:
  // Sums (a, b, c) over the agents in agent-id order: returns a's sum, b's and c's in *b_sum
  // and *c_sum when given.
  double reduce(std::uint32_t phase, std::uint32_t round, double a, double b, double* b_sum,
                double c = 0.0, double* c_sum = nullptr);

  std::vector<std::uint32_t> others() const;

  // Sends `values(id)` (width doubles per pose, as a block of the given rank) of the public
  // poses to each neighbour and returns the neighbours' values by pose id.
  template <class F>
  std::map<std::size_t, std::vector<double>> exchange(std::uint32_t phase, std::uint32_t round,
                                                      std::uint32_t rank, F values);

  // The two halves of exchange(), for steps that also carry a reduction: send, reduce,
  // then gather (one message step instead of two).
  template <class F>
  void send_publics(std::uint32_t phase, std::uint32_t round, std::uint32_t rank, F values);

  std::map<std::size_t, std::vector<double>> gather_publics(std::uint32_t phase,
                                                            std::uint32_t round,
                                                            std::uint32_t rank);

  // Restarts of the pipelined CG from its x when only the recurrence's residual converged.
  static constexpr std::uint32_t kMaxRestarts = 4;

  std::size_t width_of(std::uint32_t rank) const {
    return static_cast<std::size_t>(rank) * static_cast<std::size_t>(d_ + 1);
  }

  // A pose-block message of this agent's (phase, round, rank) with no entries yet.
  PoseBlockMessage block_message(std::uint32_t phase, std::uint32_t round,
                                 std::uint32_t rank) const;

  // Appends entry `id` to `m`: width_of(m.rank) zeros, whose first is returned.
  double* add_entry(PoseBlockMessage& m, std::uint32_t id) const;

  // Gathers the others' broadcasts of `mine`'s phase and round and calls f(agent, entry id,
  // the entry's width_of(rank) values) for every entry of every agent's (this agent's own:
  // `mine`), in agent-id order, so that sums come out bit-identical everywhere. Throws naming
  // `what` when a message's data does not fit its entries.
  template <class F>
  void for_each_entry(const PoseBlockMessage& mine, const char* what, F f);

  void rotations();

  // The sums of a CG step with the coarse level, in agent-id order: the three scalars of
  // reduce() and the N x d matrices V = sum of every agent's `coupling` (non-zero in the rows
  // of `touched`) and S (row k: agent k's `own`). One broadcast per agent.
  struct CoarseSums {
    double a = 0, b = 0, c = 0;
    Eigen::MatrixXd V, S;
  };
  CoarseSums coarse_reduce(std::uint32_t round, const double (&scalars)[3],
                           const Eigen::MatrixXd& coupling, const Eigen::RowVectorXd& own,
                           const std::vector<std::uint32_t>& touched);

  // The translations CG starts from: the iterate's, in the rounded frame, pose 0 at 0.
  Eigen::MatrixXd warm_start();

  // Preconditioned CG on L t = b (the translation Laplacian without the anchor pose 0), with
  // each agent's own Laplacian block as the preconditioner (solved exactly by Cholesky) and,
  // with options_.coarse_correction, one offset per block on top, in its pipelined form: one
  // message step per iteration. Stops when the residual is 1e-12 of b's or
  // (options_.settle_tolerance) the cost it could still remove is small enough.
  std::uint32_t translations(double relaxation_cost);

  // Cost of the rounded poses: internal measurements in full, cut ones half (as core's status).
  double cost();
  // This agent's share of cost().
  double cost_share() const;

  // The interface solve (rounding_interface.cpp). send_interface_share(): when the team's
  // interface is small enough, builds this block's solve and sends its share (before the Gram
  // matrix's gather, so it costs no wait of its own); every agent decides alike from the
  // layout. take_interface_shares(): gathers the shares; the first agent (sigma_agent())
  // assembles and factors Sigma, the others only check the shares (every agent factors it below
  // interface_one_factor_min_poses); false (the CG runs) when no share was sent or a block's
  // Laplacian is singular, on every agent alike.
  void send_interface_share();
  bool take_interface_shares();
  // Exact translations: forward solve, the interface residuals to the first agent, which solves
  // u = Sigma^-1 rhat and sends it to all (every agent factoring the same Sigma was most of the
  // rounding's instructions), or below interface_one_factor_min_poses one all-agent sum of
  // them and every agent's own solve; back solve; then pose 0's translation rides on
  // the cost's sum (the solve fixes another pose) and every translation is shifted by it.
  // Returns the cost; nothing (the CG runs, on every agent alike) when Sigma could not be
  // factored.
  std::optional<double> interface_translations();
  std::uint32_t sigma_agent() const { return everyone_.front(); }

  DistributedRoundingOptions options_;
  const AgentLocalData& local_;
  const BlockLayout& layout_;
  Mailbox& mail_;
  std::uint32_t self_;
  int d_;
  const std::vector<std::size_t>& own_;
  const Eigen::MatrixXd& Y_;
  std::vector<std::uint32_t> everyone_, neighbours_;
  std::map<std::size_t, Pose> poses_;  // own and neighbours' rounded poses
  Eigen::MatrixXd frame_;              // r x d: the Gram matrix's top-d eigenvectors
  bool reflected_ = false;             // last row flipped so most blocks are rotations
  std::unique_ptr<TranslationInterfaceSolve> interface_;  // the exact solve, when it runs
  bool one_factor_ = false;  // only sigma_agent() factors Sigma (interface_one_factor_min_poses)
  std::vector<double> interface_share_;  // this block's share, as sent
};

}  // namespace tessera::agent
