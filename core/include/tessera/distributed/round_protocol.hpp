#pragma once
// The round protocol of one agent: a state machine that consumes messages and emits messages.
// It holds no transport and does no math of its own (that is AgentState, block_selection and
// the momentum schemes); it decides which step comes next and what must be sent.
//
// Round k (Y^k known to the agent and, for its public poses, to its neighbours):
//   STATUS      every agent broadcasts its cost share and squared block gradient norm at Y^k;
//               once all N are in, each agent sums them in agent-id order (so every agent gets
//               bit-identical f(Y^k) and ||grad f(Y^k)||), checks stopping, and for the
//               accelerated methods the restart test of round k-1 (see below); then selects
//               the block(s) S_k.
//   EXTRAPOLATE (accelerated only, no message) every agent forms P^k from its own Y, V, and
//               its neighbours' public P^k from its copies of their Y and V: V never travels,
//               each agent evolves its copy of the neighbours' V (Vn) with the same pose-wise
//               formulas and global scalars the owners use. So an accelerated round costs the
//               same two message steps as a plain RBCD round.
//   UPDATE      the selected agents update their block and send their public Y^{k+1} poses;
//               every agent then advances its own V and its copy of the neighbours' V.
//   COARSE      (correction rounds, CoarseOptions; after the status reduction, before the
//               selection) the coarse correction moves Y^k; gathered, the solver agent waits
//               for every agent's terms (sent beside the status) and each other agent for
//               the solver's motions: one more message step.
//   Restart:    if the STATUS of round k+1 shows f(Y^k) - f(Y^{k+1}) < c ||grad f(Y^k)||^2,
//               every agent returns to Y^k, S_k redo a plain block update from Y^k (REDO_UPDATE),
//               V := Y, and the status is taken again (REDO_STATUS).
// Messages may arrive early or in any order; they are buffered by (round, phase) and used only
// when the agent reaches that step, so any correct delivery gives identical iterates.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/block_selection.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/local_rounds.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/distributed/momentum.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/distributed/round_history.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

struct ProtocolSnapshot;  // distributed/protocol_snapshot.hpp

/// Protocol steps, carried in the messages' `phase` field.
enum class ProtocolPhase : std::uint32_t {
  kInit = 0,         ///< Initial public Y poses.
  kStatus = 1,       ///< Round status at Y^k.
  kExtrapolate = 2,  ///< Retired (P^k is formed locally); the number stays reserved.
  kUpdate = 3,       ///< Public Y^{k+1} poses of the selected blocks.
  kRedoUpdate = 4,   ///< Same after a restart.
  kRedoStatus = 5,   ///< Round status after a restart.
  /// Coarse-correction rounds, gathered exchange (coarse_exchange.hpp): an agent's coarse terms
  /// for the solver agent, sent beside the status, and the solver's motions for an agent.
  kCoarseTerms = 6,
  kCoarseMotions = 7
};

/// What the protocol needs to know; identical on every agent.
struct RoundConfig {
  SelectionRule selection = SelectionRule::kGreedy;
  bool parallel = false;
  std::uint64_t seed = 1;
  double grad_norm_tol = 0.01;
  int max_rounds = 10000;
  double rel_cost_decrease_tol = 0.0;
  BlockUpdateOptions update;
  /// Null for plain RBCD; otherwise RBCD++ or IRBCD (each agent keeps its own clone).
  const MomentumScheme* scheme = nullptr;
  /// Two-level rounds: the blocks' rigid coarse correction (coarse_correction.hpp).
  CoarseOptions coarse;
  /// Only blocks with a gradient above a bound work and send (local_rounds.hpp). Not with
  /// `coarse` (its rounds need every block's terms and move every block).
  LocalRoundOptions local;
};

class RoundProtocol : public AgentProcess {
 public:
  RoundProtocol(AgentState& state, const BlockLayout& layout, const RoundConfig& config);

  std::vector<OutgoingMessage> start() override;
  /// Instead of start(), where every agent of the run already holds its neighbours' public
  /// poses of the start (a caller's exchange of the same poses just before): `neighbours` are
  /// they (problem().neighbors() order, the start's rows), taken as the opening exchange would
  /// take them, and round 0's status goes out at once. Every agent of the run must start so.
  std::vector<OutgoingMessage> start_with_neighbours(const Eigen::MatrixXd& neighbours);
  /// Consumes one message addressed to this agent. Throws std::runtime_error on a message
  /// that cannot belong to this run (bad sender, wrong shape, unexpected pose).
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;

  /// Instead of start(): continues from `snapshot` (taken by this agent at round k, see
  /// protocol_snapshot.hpp) and emits round k's status. When every agent resumes from its
  /// snapshot of the same round, the iterates are bit-identical to the uninterrupted run.
  /// Throws std::runtime_error when the snapshot does not fit this agent (id, sizes).
  std::vector<OutgoingMessage> resume(const ProtocolSnapshot& snapshot);
  /// Called with a snapshot each time a round's status is about to be sent (not for the
  /// status retaken after an adaptive restart), i.e. at every consistent point.
  void set_round_observer(std::function<void(const ProtocolSnapshot&)> observer) {
    observer_ = std::move(observer);
  }
  /// The state at this moment as a snapshot (meaningful at a consistent point: inside the
  /// round observer).
  ProtocolSnapshot snapshot() const;

  bool done() const override { return done_; }
  /// The senders of the step it waits for whose message has not been handled yet.
  std::size_t messages_needed() const override;
  /// The senders counted by messages_needed(), with the step's round and phase.
  std::optional<AwaitedMessages> awaited() const override;
  int rounds() const { return round_; }
  int restarts() const { return restarts_; }
  /// Coarse corrections that moved the blocks (CoarseOptions), and the f they removed in total.
  int coarse_corrections() const { return coarse_corrections_; }
  double coarse_decrease() const { return coarse_decrease_; }
  /// grad_norm, max_rounds, relative_decrease, or stalled (the cost and gradient norm
  /// repeated bit for bit for max(20, 10 x blocks) rounds: no update is accepted any more).
  const std::string& stop_reason() const { return stop_reason_; }
  const RoundHistory& trace() const { return trace_; }
  const AgentState& state() const { return state_; }

 private:
  using Inbox = MessageGate::Inbox;  // by sender: processed in id order
  void expect(std::uint32_t round, ProtocolPhase phase, std::vector<int> senders);
  void pump(std::vector<OutgoingMessage>& out);
  void complete(Inbox& inbox, std::vector<OutgoingMessage>& out);
  void begin_status(ProtocolPhase phase, std::vector<OutgoingMessage>& out);
  void after_status(ProtocolPhase phase, const Inbox& inbox, std::vector<OutgoingMessage>& out);
  void begin_update(std::vector<OutgoingMessage>& out);
  void send_poses(const Eigen::MatrixXd& X, BlockKind kind, ProtocolPhase phase,
                  const std::vector<int>& recipients, std::vector<OutgoingMessage>& out);
  bool selected(int block) const;
  std::vector<int> selected_neighbours() const;
  // Local rounds: whether this agent's block (or neighbour copy slot k's owner) is active.
  bool active_self() const { return !local_ || local_->active(state_.id()); }
  // Local rounds: the neighbour copies of inactive blocks' poses are set to Yn in `copy`.
  void freeze_inactive_neighbours(Eigen::MatrixXd& copy) const;
  // Local rounds: keeps the active blocks of the selection (a greedy one when none is), and
  // records who moves this round.
  void select_local(ClassScore class_score, const std::vector<double>& scores);
  bool frozen_ = false;  // local rounds: this block is inactive and V == Y

  AgentState& state_;
  const BlockLayout& layout_;
  RoundConfig config_;
  std::unique_ptr<MomentumScheme> scheme_;
  MomentumCoefficients coeff_;
  std::optional<LocalRounds> local_;
  std::vector<int> neighbour_owner_;  // block of each neighbour copy slot (local rounds)

  int round_ = 0;
  ProtocolPhase phase_ = ProtocolPhase::kInit;  // the step waited for (gate_.step())
  MessageGate gate_;
  std::vector<int> selection_;
  double f_prev_ = 0.0, gsq_prev_ = 0.0;
  // Whether `rec` and the recent rounds show an iterate that no longer moves.
  bool stalled(const RoundRecord& rec) const;
  bool done_ = false;
  int restarts_ = 0;
  int coarse_corrections_ = 0;
  double coarse_decrease_ = 0.0;
  // Solves the coarse problem from the status inbox and moves the blocks; returns the change
  // of f (<= 0).
  // `last_decrease`: f's decrease over the last round (gates the correction, min_gain).
  double coarse_correct(const Inbox& inbox, double last_decrease);
  // The coarse problem solved from every agent's terms: over the smoothed coarse space's
  // aggregates when the state has one, else over the blocks.
  CoarseResult solve_coarse_terms(const std::vector<const std::vector<double>*>& terms) const;
  // Moves this agent's blocks by the coarse motions (as the space above defines them) and
  // counts the correction and its decrease of f.
  void apply_coarse_motions(const std::vector<Eigen::MatrixXd>& motions, double decrease);
  // Gathered exchange: the solver's step (all terms in) and the others' (the motions in).
  void solve_gathered_coarse(const Inbox& inbox, std::vector<OutgoingMessage>& out);
  void take_coarse_motions(const Inbox& inbox, std::vector<OutgoingMessage>& out);
  // The coarse unknowns each agent moves by (coarse_exchange.hpp); the solver fills all.
  const std::vector<int>& coarse_unknowns(int agent);
  std::vector<std::vector<int>> coarse_unknowns_;
  // The status step's outcome while the gathered correction is in flight.
  struct HeldStatus {
    RoundRecord rec;
    double f = 0.0, gsq = 0.0;
    std::vector<double> norms;
  } held_;
  // The rest of the status step (after any coarse correction): selection and update.
  void continue_round(RoundRecord rec, double f, double gsq, const std::vector<double>& norms,
                      std::vector<OutgoingMessage>& out);
  std::string stop_reason_;
  RoundHistory trace_;  // snapshots copy it every round: cheap copies
  std::chrono::steady_clock::time_point start_time_;
  std::function<void(const ProtocolSnapshot&)> observer_;
};

}  // namespace tessera
