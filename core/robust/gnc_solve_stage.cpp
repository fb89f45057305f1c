// GncSolveStage (gnc_solve_stage.hpp): each GNC step's certified solve, its layout and iterate.

#include "robust/gnc_solve_stage.hpp"

#include <limits>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <utility>

#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_solve_setup.hpp"

namespace tessera {

GncSolveStage::GncSolveStage(const GncAgentInput& in, const GncDistributedOptions& options,
                             bool known_connected, Eigen::MatrixXd start)
    : in_(in),
      options_(options),
      known_connected_(known_connected),
      start_(std::move(start)),
      layout_(
          std::make_unique<BlockLayout>(make_block_layout(in.num_poses, in.structure, in.owner))) {}

void GncSolveStage::drop(const std::vector<std::uint64_t>& dropped) {
  auto layout = std::make_unique<BlockLayout>(
      make_block_layout(in_.num_poses, structure_without(in_.structure, dropped), in_.owner));
  // The state refers to the layout: keep the iterate as the next start, then replace both.
  if (state_) start_ = state_->Y;
  pass_grad_norm_ = std::numeric_limits<double>::quiet_NaN();
  solve_.reset();
  state_.reset();
  layout_ = std::move(layout);
}

void GncSolveStage::to_kept_set(const std::vector<std::uint64_t>& rejected) {
  gnc_kept_measurements(in_.measurements, in_.measurement_index, rejected, kept_, kept_index_);
  drop(rejected);
  kind_ = GncSolveKind::kInlierPass;
}

bool GncSolveStage::pass_refines() const {
  return tessera::pass_refines(options_, *layout_, in_.d);
}

bool GncSolveStage::gnc_refines() const {
  return tessera::gnc_refines(options_, *layout_, in_.d);
}

void GncSolveStage::open(bool weighted, bool capped, bool trial_poses,
                         const std::vector<double>& weights,
                         const std::vector<std::uint64_t>& rejected) {
  solve_.reset();
  // GNC's weighted solves (not the first, plain one) by Newton steps where the interface fits.
  // A solve again by rounds (solve_again_by_rounds()) solves the same weights as the step.
  const bool again = weighted && rounds_next_;
  rounds_next_ = false;
  newton_steps_ = weighted && !again && gnc_refines();
  solve_options_ = gnc_solve_options(options_, kind_, capped, newton_steps_);
  if (weighted && !again) {
    gnc_newton_steps_ = (weighted_solves_ == 0 || gnc_newton_steps_) && newton_steps_;
    ++weighted_solves_;
  }
  std::vector<Measurement> measurements;
  if (kind_ == GncSolveKind::kGnc)
    measurements = gnc_solve_measurements(in_.measurements, weights, weighted, known_connected_);
  else
    measurements = kept_;
  const Eigen::MatrixXd Y = state_ ? state_->Y : start_;
  if (newton_steps_) step_start_ = Y;  // solve_again_by_rounds() may return there
  if (kind_ == GncSolveKind::kInlierPass) last_pass_start_ = Y;
  state_ = std::make_unique<AgentState>(in_.id, in_.d, *layout_, measurements, Y,
                                        solve_options_.block_update);
  if (solve_options_.refine.enabled &&
      solve_options_.refine.coarse == NewtonRefineOptions::Coarse::kSmoothed)
    // The refinement's coarse space over the graph this solve works on, as the in-process
    // solve of the same graph builds it (every agent the same, no message).
    state_->use_refine_space(std::make_shared<const CoarseSpace>(
        make_coarse_space(in_.num_poses, structure(rejected), in_.owner,
                          solve_options_.refine.coarse_space_options())));
  solve_ = std::make_unique<CertifiedAgent>(*state_, *layout_, solve_options_);
  start_known_ = false;
  trial_pending_ = poses_sent_early_ = poses_early_stale_ = false;
  trials_taken_ = 0;
  if (kind_ == GncSolveKind::kInlierPass && trial_poses)
    solve_->set_trial_observer([this](const Eigen::MatrixXd& Y, const Eigen::MatrixXd&) {
      // Every trial of the pass: which one ends it is known only after its sums.
      trial_Y_ = Y;
      trial_pending_ = true;
    });
  else if (newton_steps_ && trial_poses)
    solve_->set_trial_observer([this](const Eigen::MatrixXd& Y, const Eigen::MatrixXd& Yn) {
      // One trial per solve (a single Newton step); after rounds the iterate the last pose
      // exchange holds is not the solve's start, so those take the exchange of their own.
      if (poses_sent_early_ || trial_pending_ || solve_->total_rounds() > 0) return;
      trial_Y_ = Y;
      trial_Yn_ = Yn;
      trial_pending_ = true;
    });
}

void GncSolveStage::know_start(double grad_norm) {
  solve_->set_known_start(grad_norm);
  start_known_ = true;
}

bool GncSolveStage::may_start_at_refinement() const {
  const bool weighted = newton_steps_ && options_.robust.exchanges_ride_along;
  const bool pass =
      kind_ == GncSolveKind::kInlierPass && options_.robust.kept_solves_start_at_refinement;
  return (weighted || pass || start_known_) && solve_->can_start_at_refinement();
}

std::vector<OutgoingMessage> GncSolveStage::start_at_refinement(const Eigen::MatrixXd& neighbours) {
  state_->reset_iterate(state_->Y, neighbours);
  return solve_->start_at_refinement();
}

const Eigen::MatrixXd* GncSolveStage::take_trial() {
  if (!trial_pending_) return nullptr;
  trial_pending_ = false;
  ++trials_taken_;
  if (kind_ != GncSolveKind::kInlierPass) poses_sent_early_ = true;
  return &trial_Y_;
}

std::uint32_t GncSolveStage::last_accepted_trial() const {
  // The refinements' trials in order, one trace record each (the same on every agent: the
  // verdicts are on summed values); 0 when none was accepted or not every trial was handed out.
  std::uint32_t t = 0, last = 0;
  for (const NewtonRefineResult& r : solve_->refines())
    for (const NewtonRefineStep& step : r.trace) {
      ++t;
      if (step.accepted) last = t;
    }
  return t == trials_taken_ ? last : 0;
}

void GncSolveStage::judge_early_poses() {
  // The trial's poses are the iterate's when the step was accepted (the same on every agent:
  // the verdict is on summed values); otherwise the iterate is the solve's start.
  const std::vector<NewtonRefineResult>& r = solve_->refines();
  poses_early_stale_ = !(r.size() == 1 && r.front().accepted_steps == 1);
}

bool GncSolveStage::newton_step_untrusted(double trust) const {
  if (!newton_steps_ || trust <= 0 || solve_->total_rounds() > 0) return false;
  // The last accepted step is where the iterate is (its trial point).
  const NewtonRefineStep* last = nullptr;
  for (const NewtonRefineResult& r : solve_->refines())
    for (const NewtonRefineStep& step : r.trace)
      if (step.accepted) last = &step;
  return last == nullptr || last->actual < trust * last->predicted;
}

void GncSolveStage::solve_again_by_rounds() {
  rounds_next_ = true;
  state_->Y = step_start_;
}

void GncSolveStage::tally() {
  if (kind_ == GncSolveKind::kFinal) {
    final_rounds_ += solve_->total_rounds();
    return;
  }
  if (kind_ == GncSolveKind::kInlierPass) pass_grad_norm_ = last_grad_norm();
  gnc_rounds_ += solve_->total_rounds();
  gnc_solve_stages_ += opened_solve_stages(solve_->solves());
  gnc_refine_steps_ += message_steps(solve_->refines());
}

double GncSolveStage::last_cost() const {
  if (solve_->solves().empty() || solve_->solves().back().trace.empty())
    return std::numeric_limits<double>::quiet_NaN();
  return solve_->solves().back().trace.back().cost;
}

double GncSolveStage::last_grad_norm() const {
  if (solve_->solves().empty() || solve_->solves().back().trace.empty())
    return std::numeric_limits<double>::quiet_NaN();
  return solve_->solves().back().trace.back().grad_norm;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> GncSolveStage::structure(
    const std::vector<std::uint64_t>& rejected) const {
  return kind_ == GncSolveKind::kGnc ? in_.structure : inlier_structure(in_.structure, rejected);
}

}  // namespace tessera
