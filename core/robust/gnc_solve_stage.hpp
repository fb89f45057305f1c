#pragma once
// The solve stage of the distributed GNC (GncAgent): the certified solve each GNC step runs (the
// first plain one, the weighted ones, the inlier passes, the final one), the block layout it
// works on, its iterate between solves, and what the finished solves add up to. GncAgent's state
// machine decides which solve comes next and tags its messages with the GNC step; this holds
// what the solve itself needs, so the state machine does not carry it.
//
// A weighted solve by a single Newton step may hand out its trial point (take_trial()): its
// public poses travel beside the trial's sums as the step's pose exchange, so the exchange after
// the solve waits for nothing (poses_sent_early()). When the trial is not accepted
// (poses_early_stale()) the iterate has not moved since the last pose exchange, whose poses
// stay.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <vector>

namespace tessera {

class GncSolveStage {
 public:
  /// `in` and `options` must outlive the stage. `known_connected`: the known inliers connect
  /// the poses (GncLocalTerms::known_connected). The first solve starts from `start` (own block,
  /// lifted).
  GncSolveStage(const GncAgentInput& in, const GncDistributedOptions& options, bool known_connected,
                Eigen::MatrixXd start);

  /// The start of the next solve when no iterate is held yet (before the first solve): another
  /// start (the start vote's winner).
  void set_start(Eigen::MatrixXd Y) { start_ = std::move(Y); }
  /// The solves from here on without the measurements `dropped` (ascending, file positions); the
  /// iterate is kept as the next solve's start.
  void drop(const std::vector<std::uint64_t>& dropped);
  /// The inlier passes from here on: the kept set (all but `rejected`, ascending) and its layout.
  void to_kept_set(const std::vector<std::uint64_t>& rejected);
  /// The final solve of the kept set comes next.
  void to_final() { kind_ = GncSolveKind::kFinal; }

  /// Sets up the next solve of the current kind from the iterate: `weighted` (GNC's weighted
  /// solve, with the current `weights` per GncAgentInput::measurements), `capped` (an inlier pass
  /// stopped at RobustOptions::recheck_max_rounds), `trial_poses` (a single Newton step hands
  /// out its trial point; an inlier pass every trial point), `rejected` (the current rejected set:
  /// the passes' coarse space).
  void open(bool weighted, bool capped, bool trial_poses, const std::vector<double>& weights,
            const std::vector<std::uint64_t>& rejected);
  /// Before the opened solve starts: its start is the iterate, where the team's last solve of
  /// the same problem ended with summed gradient `grad_norm` (CertifiedAgent::set_known_start).
  void know_start(double grad_norm);
  /// The opened solve may start at its refinement (its rounds would open with a pose exchange
  /// just held and stop at their first status): a weighted solve by Newton steps, or a solve
  /// whose start is known (know_start) within its rounds' tolerance.
  bool may_start_at_refinement() const;
  /// The opened solve's first messages: from its rounds, or (may_start_at_refinement) from its
  /// refinement with the neighbours' poses `neighbours` of the iterate (state().problem()'s
  /// neighbours, in that order).
  std::vector<OutgoingMessage> start() { return solve_->start(); }
  std::vector<OutgoingMessage> start_at_refinement(const Eigen::MatrixXd& neighbours);
  /// The trial point to publish beside its sums, once (nullptr when none is pending). A weighted
  /// solve hands out its one trial; an inlier pass opened with `trial_poses` every trial.
  const Eigen::MatrixXd* take_trial();
  /// Trials handed out since the solve opened (the last one's number, from 1).
  std::uint32_t trials_taken() const { return trials_taken_; }
  /// After an inlier pass: the number of its last accepted trial, whose point the iterate is,
  /// or 0 (none accepted, or not every trial handed out).
  std::uint32_t last_accepted_trial() const;
  /// The last trial point's neighbour poses (state().problem().neighbors() order, the trial's
  /// rows): what a weight update at that point reads beside the own block.
  const Eigen::MatrixXd& trial_neighbours() const { return trial_Yn_; }
  /// After the solve: whether the early poses are the iterate's (the step was accepted).
  void judge_early_poses();
  /// Adds the ended solve's rounds, stages and refinement message steps to the totals.
  void tally();
  /// The ended solve's summed cost and gradient (its last trace record), NaN without one.
  double last_cost() const;
  double last_grad_norm() const;

  GncSolveKind kind() const { return kind_; }
  CertifiedAgent& solve() { return *solve_; }
  const CertifiedAgent& solve() const { return *solve_; }
  AgentState& state() { return *state_; }
  const AgentState& state() const { return *state_; }
  /// The iterate (own block, lifted), or the next start before the first solve.
  const Eigen::MatrixXd& iterate() const { return state_ ? state_->Y : start_; }
  /// The iterate, or the next start while no solve has run (GNC ended at its first weights:
  /// RobustOptions::weigh_at_start).
  void set_iterate(Eigen::MatrixXd Y) {
    (state_ ? state_->Y : start_) = std::move(Y);
    pass_grad_norm_ = std::numeric_limits<double>::quiet_NaN();
  }
  const BlockLayout& layout() const { return *layout_; }
  bool pass_refines() const;  // the passes hand over to the Newton refinement (gnc_solve_setup)
  // GNC's weighted solves on the current layout are Newton steps (gnc_solve_setup).
  bool gnc_refines() const;

  bool poses_sent_early() const { return poses_sent_early_; }
  bool poses_early_stale() const { return poses_early_stale_; }
  /// Every weighted solve so far was a Newton step, and there was one (a solve again by rounds,
  /// solve_again_by_rounds(), is not counted: the weights it solves for are a Newton step's).
  bool newton_steps_only() const { return gnc_newton_steps_; }
  /// The ended solve was a weighted one by Newton steps whose model did not hold at its end
  /// (RobustOptions::newton_step_trust `trust` > 0): no step accepted, or the last accepted one
  /// lowered f by less than `trust` times its predicted decrease. The same on every agent
  /// (summed values).
  bool newton_step_untrusted(double trust) const;
  /// The iterate goes back to the ended Newton step's start, and the next weighted solve (of
  /// the same weights) runs by rounds, once.
  void solve_again_by_rounds();

  const std::vector<Measurement>& kept() const { return kept_; }
  const std::vector<std::uint64_t>& kept_index() const { return kept_index_; }
  const Eigen::MatrixXd& last_pass_start() const { return last_pass_start_; }
  /// The summed gradient at the iterate where the last inlier pass ended there (its last
  /// record); NaN once the iterate or the layout changed since, or without a record.
  double pass_grad_norm() const { return pass_grad_norm_; }
  int gnc_rounds() const { return gnc_rounds_; }
  int final_rounds() const { return final_rounds_; }
  int gnc_refine_steps() const { return gnc_refine_steps_; }
  int gnc_solve_stages() const { return gnc_solve_stages_; }

 private:
  // Endpoints of the measurements the solve works on, file order: the kept set for the passes
  // and the final solve, the whole graph for GNC's solves.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure(
      const std::vector<std::uint64_t>& rejected) const;

  const GncAgentInput& in_;
  const GncDistributedOptions& options_;
  bool known_connected_;
  GncSolveKind kind_ = GncSolveKind::kGnc;
  Eigen::MatrixXd start_;
  DistributedOptions solve_options_;  // the running solve's options
  std::unique_ptr<BlockLayout> layout_;
  std::unique_ptr<AgentState> state_;
  std::unique_ptr<CertifiedAgent> solve_;
  bool newton_steps_ = false;   // the opened solve is a weighted one by Newton steps
  bool rounds_next_ = false;    // solve_again_by_rounds(): the next weighted solve by rounds
  Eigen::MatrixXd step_start_;  // the opened Newton step's start
  bool start_known_ = false;    // know_start() for the opened solve
  double pass_grad_norm_ = std::numeric_limits<double>::quiet_NaN();
  bool gnc_newton_steps_ = false;
  int weighted_solves_ = 0;
  Eigen::MatrixXd trial_Y_, trial_Yn_;
  bool trial_pending_ = false, poses_sent_early_ = false, poses_early_stale_ = false;
  std::uint32_t trials_taken_ = 0;
  std::vector<Measurement> kept_;
  std::vector<std::uint64_t> kept_index_;
  Eigen::MatrixXd last_pass_start_;
  int gnc_rounds_ = 0, final_rounds_ = 0, gnc_refine_steps_ = 0;
  int gnc_solve_stages_ = 0;  // before the final solve
};

}  // namespace tessera
