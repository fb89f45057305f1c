#pragma once
// One agent's whole certified sequence, as a single state machine for any driver:
//   stage 0: solve at rank r (RoundProtocol)      stage 3: solve at rank r + 1
//   stage 1: certify (CertificateProtocol)        stage 4: certify
//   stage 2: escape  (SaddleEscapeProtocol)       ...
// Each rank is first solved to the solver's own gradient tolerance. A certificate that holds
// there ends the sequence. One that does not is inconclusive (Lambda(X) is off by the
// residual gradient): the same rank is refined (the solve stage after the certify stage, the
// escape stage number is skipped) and certified again; only a failure at the refined point
// leads to the escape. With the Newton refinement on (NewtonRefineOptions::enabled, the
// default) that stage's rounds stop at once and the Newton refinement refines (sphere2500 at
// N = 5: one Newton step of 29 CG iterations instead of 68 more rounds to 1e-4); with it off,
// the rounds continue to StaircaseOptions::grad_norm_tol.
// It stops after a solve when certification is off, after a certificate that holds, at the
// staircase's rank cap, or when no escape direction / step exists. Every message carries its
// stage in the phase field (stage_tag.hpp); messages of a later stage from faster agents are
// kept until this agent gets there. Every agent takes the same stage decisions because they
// follow from reductions summed in agent-id order. With certification off, it sends exactly
// RoundProtocol's messages.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <tessera/certification/distributed_certificate.hpp>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/distributed/saddle_escape.hpp>
#include <tessera/distributed/stage_records.hpp>
#include <utility>
#include <vector>

namespace tessera {

class CertifiedAgent : public AgentProcess {
 public:
  /// `state`, `layout` and `options` must outlive the agent. options.certify switches the
  /// certificate (and staircase) on.
  CertifiedAgent(AgentState& state, const BlockLayout& layout, const DistributedOptions& options);

  std::vector<OutgoingMessage> start() override;
  /// Instead of start(): the first solve stage continues from `snapshot` (a coordinated
  /// rollback, see RoundProtocol::resume); the later stages follow as usual.
  std::vector<OutgoingMessage> resume(const ProtocolSnapshot& snapshot);
  /// Before start(): the state's neighbour copies (AgentState::Yn) are the neighbours' current
  /// poses and `grad_norm` is ||grad f|| at the start point as the team last summed it, in a
  /// solve of the same problem that ended there (the same on every agent). Where that settles
  /// the first solve stage's rounds at their round-0 status (can_start_at_refinement()), start()
  /// begins at the refinement (start_at_refinement()).
  void set_known_start(double grad_norm) { known_grad_norm_ = grad_norm; }
  /// Whether the first solve stage's rounds would stop at their first status and hand over to
  /// the Newton refinement: their hand-over gradient is infinite, or the known start's gradient
  /// (set_known_start) is within half their tolerance (the rounds' own sum of it differs only
  /// by rounding); and the refinement follows such a stop. Then start_at_refinement() may
  /// replace start(). The same on every agent (options, layout and the known sum).
  bool can_start_at_refinement() const;
  /// Instead of start(), where can_start_at_refinement() holds and the state's neighbour copies
  /// (AgentState::Yn) are the neighbours' current poses, as every agent of the run knows: the
  /// first solve stage begins at its Newton refinement, without the rounds' opening pose
  /// exchange and round-0 status (the refinement takes its own). The stage's record has no
  /// rounds and SolveStageRecord::opened false; its trace is the refinement's point. The
  /// certificate, where on, follows as after the rounds. Every agent of the run must start so.
  std::vector<OutgoingMessage> start_at_refinement();
  /// Instead of start(), where every agent of the run already holds its neighbours' public
  /// poses of the start, `neighbours` (problem().neighbors() order): the first solve stage's
  /// rounds begin without their opening pose exchange (RoundProtocol::start_with_neighbours),
  /// the same iterates. Every agent of the run must start so.
  std::vector<OutgoingMessage> start_with_neighbours(const Eigen::MatrixXd& neighbours);
  /// Observer of the FIRST solve stage's consistent points (RoundProtocol::set_round_observer):
  /// snapshots of later stages would not be resumable from stage 0.
  void set_round_observer(std::function<void(const ProtocolSnapshot&)> observer) {
    observer_ = std::move(observer);
  }
  /// Observer of the trial points of the Newton refinements this agent runs
  /// (NewtonRefineProtocol::set_trial_observer).
  void set_trial_observer(TrialObserver observer) { trial_observer_ = std::move(observer); }
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  /// The running stage's count (messages of later stages are kept aside, not counted).
  std::size_t messages_needed() const override;
  /// The current stage's awaited messages, with the stage-tagged phase they carry on the wire.
  std::optional<AwaitedMessages> awaited() const override;

  const std::vector<SolveStageRecord>& solves() const { return solves_; }
  const std::vector<CertifyStageRecord>& certificates() const { return certificates_; }
  const std::vector<EscapeStageRecord>& escapes() const { return escapes_; }
  /// The Newton refinements run (options.refine), in order.
  const std::vector<NewtonRefineResult>& refines() const { return refines_; }
  /// nullopt when certification is off; otherwise the last certificate held at a point where
  /// the solve converged (stopped on its gradient or relative-decrease test).
  std::optional<bool> certified() const;
  int final_rank() const { return state_.rank(); }
  /// Sums over the solve stages.
  int total_rounds() const;
  /// total_rounds() and the rounds of the solve stage running now (total_rounds() counts a
  /// stage once it has ended).
  int rounds_so_far() const {
    const bool solving = !done_ && solve_ && current_ == solve_.get();
    return total_rounds() + (solving ? solve_->rounds() : 0);
  }
  int total_restarts() const;
  /// Sums of the certificate's LOBPCG iterations and of the escapes' line-search trials.
  int certificate_iterations() const;
  int escape_trials() const;
  std::uint32_t stage() const { return stage_; }
  /// While a certificate stage runs: its iterations so far and its current lambda_min
  /// estimate (for progress reports); nullopt in the other stages.
  std::optional<std::pair<std::uint32_t, double>> certificate_progress() const {
    if (!certify_ || current_ != certify_.get()) return std::nullopt;
    return std::make_pair(certify_->iteration(), certify_->ritz_value());
  }
  /// While a Newton refinement runs: its progress (NewtonRefineProtocol::progress());
  /// nullopt in the other stages.
  /// Whether a Newton refinement runs (from its start(), before its first sums are in).
  bool refining() const { return refine_ && current_ == refine_.get(); }
  std::optional<NewtonRefineProtocol::Progress> refine_progress() const {
    if (!refine_ || current_ != refine_.get()) return std::nullopt;
    return refine_->progress();
  }

 private:
  void begin(std::uint32_t stage, std::vector<OutgoingMessage>& out,
             const ProtocolSnapshot* resume_from = nullptr);
  void advance(std::vector<OutgoingMessage>& out);
  /// The current solve stage's Newton refinement begins (its early messages handed over).
  void begin_refine(std::vector<OutgoingMessage>& out);
  void emit(std::vector<OutgoingMessage>&& sub, std::vector<OutgoingMessage>& out) const;
  /// Hands a message of the current stage (stage-tagged phase, as on the wire) to the running
  /// protocol; a solve stage's refinement messages wait until its refinement runs.
  void dispatch(const ProtocolMessage& message, std::vector<OutgoingMessage>& out);
  /// The running protocol's handle() of `message` with its stage taken off the phase.
  void to_current(const ProtocolMessage& message, std::vector<OutgoingMessage>& out);
  /// Keeps a message (stage-tagged phase) for a later stage, or for the current solve stage's
  /// refinement; throws std::runtime_error on a second copy.
  void keep(const ProtocolMessage& message);
  /// The current solve stage's gradient tolerance: the solver's own, or refine_tolerance()
  /// while refining an inconclusive certificate.
  double solve_tolerance() const;
  double refine_tolerance() const;
  /// Whether a converged solve with this trace is refined (NewtonRefineOptions::when).
  bool refine_wanted(const std::vector<RoundRecord>& trace) const;
  /// `--refine auto` where the team's interface fits the refinement's interface solves: the
  /// rounds hand over to it at NewtonRefineOptions::auto_interface_grad_tol.
  bool hands_over_early() const;

  AgentState& state_;
  const BlockLayout& layout_;
  const DistributedOptions& options_;
  std::uint32_t stage_ = 0;
  std::unique_ptr<RoundProtocol> solve_;
  std::unique_ptr<CertificateProtocol> certify_;
  std::unique_ptr<SaddleEscapeProtocol> escape_;
  std::unique_ptr<NewtonRefineProtocol> refine_;  // runs after the current solve stage
  std::vector<NewtonRefineResult> refines_;
  AgentProcess* current_ = nullptr;
  Eigen::MatrixXd direction_;  // the last certificate's Ritz vector (own block)
  // Messages that came early, by their stage-tagged phase: of later stages (from faster
  // agents), and of the current solve stage's refinement before it begins.
  MessageGate kept_;
  std::vector<SolveStageRecord> solves_;
  std::vector<CertifyStageRecord> certificates_;
  std::vector<EscapeStageRecord> escapes_;
  std::function<void(const ProtocolSnapshot&)> observer_;
  TrialObserver trial_observer_;
  std::optional<double> known_grad_norm_;  // set_known_start()
  Eigen::MatrixXd start_neighbours_;       // start_with_neighbours(), until the first stage opens
  bool refining_ = false;        // the current rank's solve continues at refine_tolerance()
  bool interface_fits_ = false;  // the team's interface within the refinement's interface cap
  bool done_ = false;
};

}  // namespace tessera
