#pragma once
// One agent's side of distributed GNC-TLS as a single state machine for any driver (the
// in-process driver, the DDS round loop), so both run the same code:
//
//   [with GncAgentInput::pcm: every agent's values -> agent 0, which runs the pairwise
//    consistency check (robust/pairwise_consistency.hpp) and sends every agent the closures
//    outside the largest consistent set: they start at weight 0 and stay there]
//   [with GncAgentInput::Y0_known: poses of both starts, then a vote on their TLS costs;
//    every agent starts from the cheaper]
//   solve 0 (plain; every solve before the final one is capped at
//           RobustOptions::inner_max_rounds rounds: GNC needs only a rough minimiser)
//   poses    -> neighbours: the public poses of the iterate (every weight is computed at the
//               iterate itself, not at a neighbour copy that may lag a round)
//   votes    -> every agent: largest residual^2 of the measurements it owns; the max over the
//               agents gives mu's start
//   outer step k = 1, 2, ...:
//     weights -> every agent: the TLS weights of the cut measurements it owns whose other end
//               the recipient holds, the ids of its other cut measurements of weight 0 (they
//               leave the weighted solve, so every agent must know the block adjacency), and
//               its weight spread sum w (1 - w) (the stop vote)
//     solve k (weighted, warm-started)
//     poses  -> neighbours (when another step follows; where solve k is a single Newton step
//               they, and the next weights computed at its trial point, travel beside the
//               trial's sums: RobustOptions::exchanges_ride_along, weights_ride_trial_sums)
//   rejected -> every agent: the measurements it owns with weight < 0.5
//   [with GncAgentInput::kept_set_start: kept values -> agent 0, which initializes the kept
//    set and sends each agent its block; poses of the iterate and of that start, then a vote
//    on their costs over the kept set; the first pass starts from the cheaper]
//   inlier pass p = 0.. readmission_passes: solve of the kept set to the solver's tolerance
//   (uncertified);
//     poses, then readmitted -> every agent: its rejected measurements within the bound at
//     that solution (misjudged on a rough iterate; weight 1) and its kept ones beyond it
//     (weight 0); no change anywhere ends the passes
//   final: with certification or RobustOptions::final_refine, the solve of the kept set
//          (certified with certification, ending with the Newton refinement with final_refine)
//
// Each weight is computed by one agent, the owner of the measurement's lower pose id
// (weight_owner()); the other end receives it, so both ends always use the same weight. The
// stop follows from the summed spread, identical on every agent: no central step.
// Messages carry their step in `phase` (gnc_phase()); a fast agent's messages of later steps
// wait until this agent gets there, and each exchange reads its messages in agent-id order once
// all are in (robust/gnc_mailbox.hpp).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/graph/measurement.hpp>
#include <tessera/robust/gnc_agent_result.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <utility>
#include <vector>

namespace tessera {

/// Phases of GNC step g (0 = first solve, k = k-th weighted solve, then the inlier passes and
/// the final solve):
/// g * kGncStepStride + the inner solve's stage-tagged phase (stage_tag.hpp), or + the GNC
/// exchange's own phase. The stride is a multiple of 3 * kStagePhaseStride so stage_kind() of a
/// tagged phase is still the inner stage's kind (certificate traffic is counted by it).
constexpr std::uint32_t kGncStepStride = 3000000;
/// The GNC exchanges sit after every inner stage of their step (inner stages stay below 999).
constexpr std::uint32_t kGncExchangeBase = 999000;
/// In the order they happen within a step (a message of a phase below the current one is of a
/// step this agent has left). The start vote has step 0 to itself (the first solve is step 1).
enum class GncExchange : std::uint32_t {
  kPoses = 1,
  kVotes = 2,
  kWeights = 3,
  /// The weights at a weighted solve's trial point, sent beside its sums
  /// (RobustOptions::weights_ride_trial_sums); read as the step's weight exchange when the
  /// trial is accepted. Below the exchanges that may follow it in the same step (the rejected
  /// set's, the kept set's start after an early end), whose messages must wait, not be dropped.
  kTrialWeights = 4,
  kRejected = 5,
  /// An inlier pass's trial points' poses, sent beside each trial's sums (the wire's round is
  /// the trial's number, from 1; RobustOptions::pass_poses_ride_trial_sums): the pass's pose
  /// exchange reads the last accepted one's. Below the verdict that follows it.
  kPassTrialPoses = 6,
  kReadmitted = 7,
  kKeptValues = 8,
  kKeptStart = 9,
  kCandidatePoses = 10,
  kCandidateVotes = 11,
  kPcmValues = 12,
  kPcmDropped = 13,
  kStartPoses = 14,
  kStartVotes = 15
};
inline std::uint32_t gnc_phase(std::uint32_t step, GncExchange e) {
  return step * kGncStepStride + kGncExchangeBase + static_cast<std::uint32_t>(e);
}
/// Most GNC steps the phase field can tag (the first solve, the weighted ones, the final one).
constexpr std::uint32_t kMaxGncSteps = 4294967295u / kGncStepStride;

/// What one agent starts from.
struct GncAgentInput {
  int id = 0;
  int num_agents = 1;
  int d = 0;
  std::size_t num_poses = 0;
  std::vector<int> owner;  ///< Agent of every pose 0..n-1.
  /// Endpoints of every measurement of the whole graph, in file order (the layout, the
  /// connectivity check of the kept set).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  /// The measurements touching this agent's poses, file order, and their file positions.
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;
  /// Empty, or one per measurement of the whole graph (file order): true = never
  /// down-weighted (a dpgo CSV file's is_known_inlier column).
  std::vector<bool> known_inlier;
  Eigen::MatrixXd Y0;  ///< Own block's lifted start, r x (d+1)m, ascending pose ids.
  /// Optional: the own block of a second start, the known inliers' initialization (lifted like
  /// Y0). The agents then vote before the first solve: each sums the TLS cost (known inliers
  /// r^2, the others min(r^2, c^2)) of the measurements it weighs at both starts, and every
  /// agent starts from the cheaper (Y0 on a tie). A chordal start fits every measurement,
  /// wrong ones too, and settles in a distorted solution; on clean data it is nearly the
  /// optimum. Empty: Y0.
  Eigen::MatrixXd Y0_known;
  /// The first inlier pass may start from a fresh `initialization` of the kept set instead of
  /// the GNC iterate, when that costs less over the kept set (a vote). Only for kChordal:
  /// agent 0 gathers the kept values and solves, as the chordal initialization does; the
  /// distributed initialization exists to avoid that gather, and the file's poses are no
  /// initialization of a subset. Otherwise no fresh start.
  bool kept_set_start = false;
  DistributedInit initialization = DistributedInit::kChordal;
  std::string source;  ///< Names the input in the fresh start's errors.
  /// `--robust pcm-gnc`: the pairwise consistency check before GNC. It needs every closure
  /// against every other and the odometry between their ends, a global test, so agent 0 runs
  /// it on the values the others send it (like the chordal initialization); what it decides is
  /// a pre-filter, the weights stay the owners'. Needs known inliers that connect the poses.
  bool pcm = false;
};

/// The solves of the distributed GNC: its own (the first and the weighted ones), the inlier
/// passes over the kept set, and the final solve of the kept set.
enum class GncSolveKind { kGnc, kInlierPass, kFinal };

class GncLocalTerms;      // internal: the TLS math over one agent's view
struct RecheckVerdict;    // internal: an inlier pass's re-check
class GncSolveStage;      // internal: each step's solve, its layout and iterate
class GncProbeStage;      // internal: probes after the re-check passes
class GncKeptStartVotes;  // internal: the kept set's fresh start against the iterate
class GncInlierPasses;    // internal: the inlier passes' count and which are capped
class GncMailbox;         // internal: where incoming messages go
class GncExchangeBook;    // internal: the exchanges' messages and what they carry
class GncOuterLoop;       // internal: mu, its steps and the stop decision

class GncAgent : public AgentProcess {
 public:
  /// `options` must outlive the agent. With `final_solve` false the agent is done before the
  /// certified solve of the kept set (the caller runs it, or uses the last inlier pass).
  GncAgent(GncAgentInput input, const GncDistributedOptions& options, bool final_solve = true);
  ~GncAgent() override;
  GncAgent(const GncAgent&) = delete;  // its parts refer to its input
  GncAgent& operator=(const GncAgent&) = delete;

  std::vector<OutgoingMessage> start() override;
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  std::size_t messages_needed() const override;
  std::optional<AwaitedMessages> awaited() const override;

  /// Called after every weight exchange with the outer step (1, 2, ...) and the weight this
  /// agent uses for each of its measurements (file positions, weights): what tests compare
  /// across the two ends of a cut measurement.
  void set_weight_observer(
      std::function<void(int, const std::vector<std::uint64_t>&, const std::vector<double>&)>
          observer) {
    weight_observer_ = std::move(observer);
  }

  // Results, identical on every agent once done() (rejected, counts, threshold).
  /// Every figure of GncAgentResult, read off this agent (once done()).
  GncAgentResult result() const;
  const std::vector<std::uint64_t>& rejected() const { return rejected_; }  ///< Ascending.
  int outer_iterations() const;
  std::size_t readmitted() const { return readmitted_; }  ///< Taken back by the passes.
  /// Kept by GNC, rejected by a pass (beyond the bound at the kept set's solution).
  std::size_t late_rejected() const { return late_rejected_; }
  bool weights_converged() const;
  /// Probes run after the re-check passes, and those that lowered the TLS cost and stayed.
  int probes() const;
  int probes_kept() const;
  double threshold_squared() const;
  /// Rounds of the solves before the final certified one (first, weighted, inlier passes).
  int gnc_rounds() const;
  /// Message steps (neighbour exchanges and all-agent sums) of the Newton refinements of those
  /// solves: GNC's weighted solves and the inlier passes solved to the tolerance where they hand
  /// over under `--refine auto` (gnc_solve_setup).
  int gnc_refine_steps() const;
  /// Message steps of GNC's own exchanges (the Step values other than kSolve: poses, votes,
  /// weights, rejected sets, re-check verdicts, start votes, gathers), each a wait for peers like
  /// a round: one per exchange, two per gather at agent 0 (the values in, agent 0's answer
  /// out). The same on every agent (all run the same exchanges).
  int exchange_steps() const { return exchange_steps_; }
  /// The own block at the start of the last inlier pass (what the caller of an agent without
  /// the final solve starts that pass from to get its full record).
  const Eigen::MatrixXd& last_pass_start() const;
  int total_rounds() const;
  /// The current weight of each of this agent's measurements (same order as the input's).
  const std::vector<double>& weights() const { return weights_; }
  const std::vector<std::uint64_t>& measurement_index() const { return in_.measurement_index; }
  /// The iterate: own block, lifted (after the final solve: of the kept set).
  const AgentState& state() const;
  /// The final solve (nullptr before it or without it), its layout and kept measurements.
  /// The last solve (the certified one, or the last inlier pass); valid once done().
  const CertifiedAgent& last_solve() const;
  const CertifiedAgent* final_sequence() const;
  /// Whether a final solve of the kept set follows the inlier passes (with certification or
  /// RobustOptions::final_refine); otherwise the last pass, solved to the tolerance, is the
  /// answer.
  bool final_solve_runs() const;
  /// Once done() without the final solve run here: the summed gradient at the iterate where
  /// the final solve may start at its Newton refinement (RobustOptions::
  /// kept_solves_start_at_refinement; the iterate is the last pass's end and every agent holds its
  /// neighbours' poses there), NaN where it opens with its rounds.
  double final_start_grad_norm() const { return final_start_grad_norm_; }
  const BlockLayout& layout() const;
  const std::vector<Measurement>& kept_measurements() const;
  const std::vector<std::uint64_t>& kept_index() const;

 private:
  enum class Step {
    kSolve,
    kPoses,
    kVotes,
    kWeights,
    kRejected,
    kReadmitted,
    kKeptStart,
    kCandidatePoses,
    kCandidateVotes,
    kPcm,
    kStartPoses,
    kStartVotes,
    kDone
  };
  void begin_solve(std::vector<OutgoingMessage>& out);
  void begin_exchange(Step step, std::vector<OutgoingMessage>& out);
  void after_solve(std::vector<OutgoingMessage>& out);
  void after_exchange(std::vector<OutgoingMessage>& out);
  // What the exchange of each kind sends (the current step's): the poses of the iterate and
  // of a second start; a status to every other agent; the weights (true when agent 0 takes the
  // others' values beside them).
  void send_poses(std::uint32_t phase, std::vector<OutgoingMessage>& out);
  void send_status(std::uint32_t phase, std::vector<OutgoingMessage>& out);
  bool send_weights(std::uint32_t phase, std::vector<OutgoingMessage>& out);
  // after_exchange() of the steps with more to decide.
  void after_weights(std::vector<OutgoingMessage>& out);
  void after_rejected(std::vector<OutgoingMessage>& out);
  void after_pcm(std::vector<OutgoingMessage>& out);
  // The vote's sums: the kept set's cost at the iterate and at the fresh start.
  void after_candidate_votes(std::pair<double, double> sums, std::vector<OutgoingMessage>& out);
  // RobustOptions::kept_vote_rides_weights: the weights messages carry each agent's cost over
  // the kept set at TLS's verdict (the same on every agent: options and data only).
  bool kept_vote_rides_weights() const;
  // This agent's cost over the measurements it weighs that an early end at this update keeps
  // (weights `w` at TLS's verdict, as after_weights maps them), at `Y` and its neighbours; 0
  // without kept_vote_rides_weights().
  double kept_cost_at(const std::vector<double>& w, const Eigen::MatrixXd& Y,
                      const Eigen::MatrixXd& neighbours) const;
  void after_start_votes(std::vector<OutgoingMessage>& out);
  void after_verdict(std::vector<OutgoingMessage>& out);
  // A re-check verdict that changes nothing: a pass to the tolerance, a probe, or the end.
  void after_unchanged_verdict(std::vector<OutgoingMessage>& out);
  // One message of the running solve, handed to it; after_solve() when that ends the solve.
  void to_solve(const ProtocolMessage& m, std::vector<OutgoingMessage>& out);
  // The current exchange's messages once all are in: read, then after_exchange().
  void take_exchange(std::vector<OutgoingMessage>& out);
  GncExchange exchange() const;  // the current step's, as this agent sends or awaits it
  // The inner solve's messages, tagged with this GNC step; with them the trial point's poses
  // when the solve just handed one out (send_poses_with_trial).
  void pass_on(std::vector<OutgoingMessage> solve_out, std::vector<OutgoingMessage>& out);
  // Whether this weighted solve's trial point, if accepted, is the iterate whose poses the next
  // weight update needs: a single Newton step, not the last weighted solve.
  bool send_poses_with_trial() const;
  // The solves from here on without the measurements `dropped` (ascending); the iterate is kept.
  void solve_without(const std::vector<std::uint64_t>& dropped);
  // The count of owned weights that crossed 1/2 (only those that fell below it with
  // RobustOptions::mu_step_hold kFalls), at the iterate `Y` with its neighbours' poses (the
  // exchange book's columns) into `w`, leaving the measurements flagged in `skip` as they are.
  int weights_at(double mu, const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours,
                 const std::vector<bool>& skip, std::vector<double>& w) const;
  // One weight update at a point, with all that goes out beside it: the same for the update at
  // the iterate and at a trial point.
  struct WeightUpdate {
    std::vector<double> weights;
    std::vector<std::uint64_t> zero_cut;       // cut measurements of weight 0 (others' too)
    std::pair<double, double> vote{0.0, 0.0};  // (spread, crossed)
    double near = 0.0;       // near-bound count (RobustOptions::jump_band; 1 when off)
    double kept_cost = 0.0;  // kept_cost_at
  };
  // The update from weights `w` at `Y` with its neighbours' poses, `skip` left as they are.
  WeightUpdate weight_update(std::vector<double> w, const Eigen::MatrixXd& Y,
                             const Eigen::MatrixXd& neighbours,
                             const std::vector<bool>& skip) const;
  // Makes `u` this agent's weights and its own entries of the exchange (its vote, near-bound
  // count and kept cost); broadcast_weights() sends it to every other agent.
  void adopt_weights(WeightUpdate u);
  void broadcast_weights(std::uint32_t phase, const WeightUpdate& u,
                         std::vector<OutgoingMessage>& out) const;
  // The weight update at the trial point `Y` the solve just handed out, sent beside its sums
  // (RobustOptions::weights_ride_trial_sums); kept aside until the solve's verdict.
  void send_trial_weights(const Eigen::MatrixXd& Y, std::vector<OutgoingMessage>& out);
  // The near-bound count at `Y` (RobustOptions::jump_band; 1 when off, so GNC never ends early).
  int near_bound_at(const std::vector<bool>& skip, const Eigen::MatrixXd& Y,
                    const Eigen::MatrixXd& neighbours) const;
  // After a solve that sent them: the weight exchange from the trial's weights (this agent's kept
  // aside, the others' in) when the trial was accepted; false (the messages dropped) otherwise.
  bool begin_trial_weights(std::vector<OutgoingMessage>& out);
  // After an inlier pass that sent its trials' poses: the pose exchange from the last accepted
  // trial's; false (every trial's messages dropped) when none was.
  bool begin_pass_trial_poses(std::vector<OutgoingMessage>& out);
  void require_kept_connected() const;  // throws InputError naming the parts left
  // The vote between the iterate and the kept set's fresh start (its kind told to kept_votes_
  // before): the kept set must connect the poses, then the gather at agent 0.
  void begin_kept_start_vote(std::vector<OutgoingMessage>& out);
  // GNC's rejected set: from the last weight exchange where there was one, else an exchange.
  void begin_rejected(std::vector<OutgoingMessage>& out);
  void begin_inlier_pass(std::vector<OutgoingMessage>& out);
  void finish(std::vector<OutgoingMessage>& out);
  void start_kept_set(std::vector<OutgoingMessage>& out);
  // After the pcm drop or the start vote (`start_voted`): the first solve, or with
  // RobustOptions::weigh_at_start after a vote, the first weight update.
  void after_step_zero(bool start_voted, std::vector<OutgoingMessage>& out);
  // RobustOptions::weigh_at_start applies after a start vote: GNC's weighted solves are Newton
  // steps, so no first solve follows the vote.
  bool weighs_at_start() const;
  void drop_inconsistent(const std::vector<std::uint64_t>& ids);
  // A probe from the current set (summed TLS cost `tls`): the measurements of `flip` change side.
  void begin_probe(double tls, std::vector<std::uint64_t> flip, std::vector<OutgoingMessage>& out);
  // Undoes the running probe (its TLS cost `rise` above the set before it; 0 when no verdict
  // judged it); the next probe of the cluster search, or one last pass.
  void restore_before_probe(std::vector<OutgoingMessage>& out, double rise = 0);

  GncAgentInput in_;
  const GncDistributedOptions& options_;
  bool final_solve_wanted_;
  std::unique_ptr<GncSolveStage> stage_;  // the running solve, its layout and the iterate
  std::uint32_t g_ = 0;                   // GNC step
  std::uint32_t first_solve_g_ = 0;       // 1 after a start vote (step 0 is the vote's)
  // The kept set's fresh start (kept_set_start, chordal): its votes against the iterate.
  std::unique_ptr<GncKeptStartVotes> kept_votes_;
  std::vector<bool> dropped_;  // per in_.measurements: outside the consistent set (pcm)
  Step step_ = Step::kSolve;
  std::unique_ptr<GncInlierPasses> passes_;  // their count, which are capped, which start solved
  std::size_t readmitted_ = 0;
  std::unique_ptr<RecheckVerdict> recheck_;  // the current re-check exchange's, every agent's
  std::size_t late_rejected_ = 0;
  std::unique_ptr<GncProbeStage> probes_;  // RobustOptions::recheck_probes, cluster_probes
  std::vector<std::uint64_t> zero_cut_;    // cut measurements of weight 0 (others' too)
  // The other agents' measurements of weight below 1/2 at the last weight exchange, and whether
  // that exchange ended GNC at TLS's verdict (RobustOptions::jump_band).
  std::vector<std::pair<std::uint64_t, double>> low_weights_;
  bool jumped_ = false;
  // The weight update at the running weighted solve's trial point (send_trial_weights).
  bool trial_weights_sent_ = false;
  WeightUpdate trial_update_;
  // The kept set's summed cost at the iterate after GNC's early end, from the last weights
  // exchange (RobustOptions::kept_vote_rides_weights): the fresh start's vote then needs no
  // exchange. Empty otherwise, and once that vote is taken.
  std::optional<double> iterate_kept_cost_;
  // The running inlier pass's trial points whose poses went out (pass_poses_ride_trial_sums).
  std::uint32_t pass_trials_sent_ = 0;
  // Agent 0 holds every measurement's value (sent beside the first weights, with
  // RobustOptions::exchanges_ride_along and the kept set's fresh start): a fresh start then
  // waits only for agent 0's answer, not for the values first. The same on every agent.
  bool values_held_ = false;
  bool gather_values_early() const;
  // The neighbours' public poses the exchange book holds are the current iterate's (a pose
  // exchange since the iterate last moved). With values_held_ the kept set's fresh start then
  // needs no pose exchange: agent 0 sends each agent its neighbours' poses of the start too.
  bool neighbours_current_ = false;
  double final_start_grad_norm_ = std::numeric_limits<double>::quiet_NaN();  // finish()
  std::unique_ptr<BlockLayout> base_;          // of every measurement: whose poses go where
  std::unique_ptr<GncLocalTerms> terms_;       // the TLS math over this agent's view
  std::vector<double> weights_;                // per in_.measurements
  std::unique_ptr<GncMailbox> mail_;           // where incoming messages go
  std::unique_ptr<GncExchangeBook> exchange_;  // the exchanges' messages and state
  std::unique_ptr<GncOuterLoop> outer_;        // mu, its steps, the outer-step count, the stop
  std::vector<std::uint64_t> rejected_;
  std::vector<std::uint64_t> gnc_rejected_;  // GNC's own set, before the passes (ascending)
  int exchange_steps_ = 0;
  bool done_ = false;
  std::function<void(int, const std::vector<std::uint64_t>&, const std::vector<double>&)>
      weight_observer_;
};

}  // namespace tessera
