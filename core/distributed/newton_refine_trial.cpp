// The trial point of a Newton step: its translations (solved exactly through the interface, or
// by the block-Jacobi translation CG), its cost and gradient sums, and the trust-region verdict
// that accepts it, backtracks along the same step or starts the next CG. The rest of the
// refinement's state machine is in newton_refine.cpp.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tessera/distributed/newton_refine.hpp>

#include "distributed/interface_solve.hpp"
#include "distributed/pipelined_cg.hpp"
#include "distributed/public_pose_messages.hpp"
#include "distributed/rigid_retraction.hpp"
#include "distributed/tangent_coarse_space.hpp"
#include "distributed/translation_interface_solve.hpp"
#include "distributed/translation_preconditioner.hpp"
#include "distributed/trust_region_rule.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera {

void NewtonRefineProtocol::try_step(const std::string& cg_stop, std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.trial_s);
  step_.cg_stop = cg_stop;
  // A projected CG's step is orthogonal to the gauge already.
  if (use_interface_ && use_gauge_ && !project_gauge_) project_step_off_gauge();
  step_.predicted = -model_;
  s_full_ = s_;
  scale_ = 1.0;
  backtracks_ = 0;
  Xt_ = retract_rigid(problem_.manifold(static_cast<int>(X_.rows())), problem_.dim(), X_, s_);
  translations_solved_ = false;
  send_public(Xt_, kTrial, out);
}

void NewtonRefineProtocol::after_trial(const MessageGate::Inbox& inbox,
                                       std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.trial_s);
  neighbours_into(inbox, Xtn_);
  if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(Xtn_);
  if (options_.translation_iterations > 0 && !translations_solved_) return start_translations(out);
  send_trial_sums(out);
}

void NewtonRefineProtocol::send_trial_sums(std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.trial_s);
  if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(Xtn_);
  double share = 0.0;
  problem_.cost(Xt_, &share);
  egrad_t_ = problem_.euclidean_gradient(Xt_);
  g_t_ = problem_.riemannian_gradient(Xt_, egrad_t_);
  std::vector<double> values{share, g_t_.squaredNorm()};
  if (trial_observer_) {
    // The block finish() would leave: the trial point on the rows in use, zero elsewhere.
    Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(state_.Y.rows(), state_.Y.cols());
    Y(rows_, Eigen::all) = Xt_;
    Eigen::MatrixXd Yn = Eigen::MatrixXd::Zero(state_.Y.rows(), Xtn_.cols());
    if (Xtn_.cols() > 0) Yn(rows_, Eigen::all) = Xtn_;
    trial_observer_(Y, Yn);
  }
  trial_coarse_g_ = ship_trial_coarse_gradient();
  if (trial_coarse_g_) {
    // Phi^T g at the trial point: accepted, it is the next step's (whose matrix is the kept
    // one), so that step needs no coarse sum of its own.
    const std::size_t at = values.size();
    values.resize(at + static_cast<std::size_t>(coarse_->size()), 0.0);
    coarse_->project(Xt_, g_t_, values.data() + at);
  }
  trial_shares_ = ship_trial_shares();
  if (trial_shares_) {
    // The block's share of Sigma at the trial point, before the verdict: accepted, agent 0
    // factors Sigma from these and its factor rides in the next interface step.
    charge_to(&result_.times.factor_s);
    const std::vector<double> mine = interface_->factor_pending(Xt_, Xtn_, egrad_t_);
    values.insert(values.end(), mine.begin(), mine.end());
  }
  trial_interface_ = ship_trial_interface();
  if (!trial_interface_) return broadcast(kTrialSums, values, out);
  // The whole interface share at the trial point, before the verdict (its gauge and forward
  // solves kept aside): accepted, the next CG starts from these with no interface step.
  swap_point_parts();
  const std::vector<double> full = interface_share(Xt_, Xtn_, egrad_t_, g_t_, true);
  std::vector<double> brief;
  if (options_.sigma_factoring == SigmaFactoring::kShipSolves) brief = brief_share(full);
  swap_point_parts();
  charge_to(&result_.times.trial_s);
  const auto with = [&](const std::vector<double>& share) {
    std::vector<double> v = values;
    v.insert(v.end(), share.begin(), share.end());
    return v;
  };
  if (options_.sigma_factoring == SigmaFactoring::kShipSolves)
    send_to_holder(kTrialSums, with(full), with(brief), out);
  else
    broadcast(kTrialSums, with(full), out);
}

bool NewtonRefineProtocol::ship_trial_interface() const {
  // As ship_trial_shares(), where Sigma's shares at each point are the interface step's whole
  // message (every agent factoring Sigma, or agent 0 solving with it).
  return options_.interface_in_trial_sums &&
         options_.sigma_factoring != SigmaFactoring::kShipFactor && interface_ && use_interface_ &&
         step_.predicted > options_.relative_decrease_tol * std::abs(f_) &&
         result_.steps + 1 < options_.max_steps;
}

bool NewtonRefineProtocol::ship_trial_coarse_gradient() const {
  // Where an accepted trial's step would keep the coarse matrix (send_coarse's test, one
  // accepted step on): the same on every agent.
  return coarse_ && keeps_coarse_matrix(!options_.coarse_multipliers, result_.coarse_assemblies,
                                        coarse_kept_steps_ + 1, options_.coarse_keep_steps);
}

bool NewtonRefineProtocol::ship_trial_shares() const {
  // Not where the step is predicted to end the refinement (its decrease below the stop's) or
  // it is the last step allowed: there the block factor would not be used.
  return options_.sigma_factoring == SigmaFactoring::kShipFactor && interface_ && use_interface_ &&
         step_.predicted > options_.relative_decrease_tol * std::abs(f_) &&
         result_.steps + 1 < options_.max_steps;
}

void NewtonRefineProtocol::after_trial_sums(const MessageGate::Inbox& inbox,
                                            std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.trial_s);
  // The sums (in id order, as reduce_in_id_order), Phi^T g's (trial_coarse_g_), then each
  // block's share of Sigma.
  const std::size_t sums =
      2 + (trial_coarse_g_ ? static_cast<std::size_t>(coarse_->size()) : std::size_t{0});
  std::vector<double> t(sums, 0.0);
  std::vector<std::vector<double>> shares;
  for (const auto& [sender, m] : inbox) {
    const auto* p = std::get_if<PoseBlockMessage>(&m);
    const bool carried = trial_shares_ || trial_interface_;
    if (!p || p->data.size() < sums || (p->data.size() > sums) != carried)
      throw std::runtime_error("newton refine: malformed trial sums from agent " +
                               std::to_string(sender));
    for (std::size_t k = 0; k < sums; ++k) t[k] += p->data[k];
    if (carried)
      shares.emplace_back(p->data.begin() + static_cast<std::ptrdiff_t>(sums), p->data.end());
  }
  const double ft = t[0], gt = std::sqrt(std::max(0.0, t[1]));
  ++result_.steps;
  const double actual = f_ - ft;
  step_.step_norm = scale_ * std::sqrt(std::max(0.0, cg_->step_norm2()));
  // Cut by the trust region (Manopt's limitedbyTR): CG stopped at its boundary or followed
  // negative curvature to it (after_sums takes both to the radius). Were only the first
  // counted, steps that meet negative curvature every time would never grow the region.
  const bool on_boundary = step_.cg_stop == "boundary" || step_.cg_stop == "negative_curvature";
  const TrustRegionVerdict verdict = judge_trust_region_step(
      f_, ft, step_.predicted, step_.step_norm, radius_, on_boundary, options_.accept_ratio);
  step_.actual = actual;
  step_.accepted = verdict.accepted;
  radius_ = verdict.radius;
  if (step_.accepted) {
    X_ = Xt_;
    Xn_ = Xtn_;
    egrad_ = egrad_t_;
    g_ = g_t_;
    f_ = ft;
    gnorm_ = gt;
    ++result_.accepted_steps;
    coarse_due_ = true;
    ++coarse_kept_steps_;
    if (trial_coarse_g_) {  // the kept matrix's step: its Phi^T g came with these sums
      coarse_g_ = Eigen::Map<const Eigen::VectorXd>(t.data() + 2, coarse_->size());
      coarse_fresh_ = false;
      coarse_due_ = false;
      ++result_.coarse_gradients_carried;
    }
    interface_due_ = true;
    refactor_due_ = true;  // each CG solve preconditioned at its own point (when asked)
    if (trial_shares_ || trial_interface_) {
      interface_->commit_pending();
      next_shares_ = std::move(shares);
      shares_ready_ = trial_shares_;
    }
    if (trial_interface_) {  // the next CG's interface step is in hand
      swap_point_parts();
      interface_carried_ = true;
    }
  } else if (trial_shares_ || trial_interface_) {
    ++result_.pending_factors_unused;
  }
  trial_shares_ = trial_interface_ = trial_coarse_g_ = false;
  step_.cost = f_;
  step_.grad_norm = gnorm_;
  result_.trace.push_back(step_);
  result_.cost = f_;
  result_.grad_norm = gnorm_;
  if (gnorm_ <= options_.grad_norm_tol) return finish("grad_norm");
  // Not at a gradient above the start's: a step cut short by the trust region lowers f little
  // (ais2klinik: after three rejected steps a short one left |grad f| at 0.51, from 0.0097).
  if (step_.accepted && actual <= options_.relative_decrease_tol * std::abs(f_) &&
      gnorm_ <= result_.initial_grad_norm)
    return finish("relative_decrease");
  if (result_.steps >= options_.max_steps) return finish("max_steps");
  if (result_.cg_iterations >= options_.max_cg_iterations) return finish("max_cg_iterations");
  if (!step_.accepted && !(radius_ > 1e-14 * std::max(1.0, X_.norm()))) return finish("stalled");
  if (!step_.accepted && backtracks_ < options_.max_backtracks) {
    // Back along the same step: the model there is known from <g, s> and <s, H s>, so no CG
    // runs again (ais2klinik's first Newton step raised f by 178 where the model predicted a
    // decrease of 0.047: three CG solves of 423, 330 and 167 iterations went to rejected steps).
    ++backtracks_;
    scale_ *= 0.25;
    s_ = scale_ * s_full_;
    step_ = NewtonRefineStep{};
    step_.radius = radius_;
    step_.cg_stop = "backtrack";
    step_.predicted = -(scale_ * gs_ + 0.5 * scale_ * scale_ * sHs_);
    Xt_ = retract_rigid(problem_.manifold(static_cast<int>(X_.rows())), problem_.dim(), X_, s_);
    translations_solved_ = false;
    send_public(Xt_, kTrial, out);
    return;
  }
  begin_cg(out);
}

void NewtonRefineProtocol::start_translations(std::vector<OutgoingMessage>& out) {
  // f at fixed rotations is quadratic in the translations: the CG's residual is minus the
  // translation columns of the Euclidean gradient at the trial point.
  charge_to(&result_.times.translations_s);
  tr_ = -problem_.euclidean_gradient(Xt_);
  if (translation_solve_) {
    // Exact: x = (2 L)^-1 r, the own block's forward solve now, its interface residual summed.
    const int w = problem_.dim() + 1;
    const Eigen::Index m = static_cast<Eigen::Index>(problem_.num_owned());
    Eigen::MatrixXd b(m, tr_.rows());
    for (Eigen::Index i = 0; i < m; ++i) b.row(i) = 0.5 * tr_.col(i * w + w - 1).transpose();
    translation_solve_->forward(b, ty_);
    const Eigen::MatrixXd rhat = translation_solve_->interface_residual(ty_);
    ++result_.translation_solves;
    std::vector<double> values(rhat.data(), rhat.data() + rhat.size());
    if (!translation_one_factor_) return broadcast(kTranslationSolve, values, out);
    // One factor: the residuals to the holder alone; the others count the step as passed (the
    // holder's message round moves on when it has them all) and wait for its u.
    const int id = state_.id();
    PoseBlockMessage msg = make_reduction_message(id, message_round_, kTranslationSolve, values);
    ++result_.reductions;
    if (id == kSigmaHolder) {
      gate_.add(id, message_round_, kTranslationSolve, msg);
      gate_.expect(message_round_, kTranslationSolve, everyone_);
      return;
    }
    out.push_back(addressed_to(static_cast<std::uint32_t>(kSigmaHolder), std::move(msg)));
    ++message_round_;
    gate_.expect(message_round_, kTranslationSolution, {kSigmaHolder});
    ++result_.reductions;
    return;
  }
  TranslationPreconditioner::keep_translations(problem_.dim(), tr_);
  tx_.setZero(Xt_.rows(), Xt_.cols());
  tcg_->restart();
  send_translation_direction(out);
}

void NewtonRefineProtocol::send_translation_direction(std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.translations_s);
  translation_preconditioner_->apply(tr_, tz_);
  // An iteration = this exchange and its sum.
  ++result_.translation_iterations;
  ++step_.translation_iterations;
  send_public(tz_, kTranslationDirection, out);
}

void NewtonRefineProtocol::after_translation_direction(const MessageGate::Inbox& inbox,
                                                       std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.translations_s);
  neighbours_into(inbox, tzn_);
  // The translation Hessian's product: the Euclidean gradient of the direction (neighbours set
  // to theirs), translation columns only; no projection (the translations are Euclidean).
  if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(tzn_);
  tw_ = problem_.euclidean_gradient(tz_);
  TranslationPreconditioner::keep_translations(problem_.dim(), tw_);
  broadcast(kTranslationSums, {frobenius_inner(tr_, tz_), frobenius_inner(tz_, tw_)}, out);
}

void NewtonRefineProtocol::after_translation_sums(const MessageGate::Inbox& inbox,
                                                  std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.translations_s);
  const std::vector<double> t = reduce_in_id_order(inbox, 2);
  const double gamma = t[0], delta = t[1];
  bool stop = !(gamma > 0);
  if (!stop) {
    const PipelinedCgIteration it = tcg_->begin(gamma, delta);
    it.update_direction(tz_, tp_);
    it.update_direction(tw_, tq_);
    if (!(it.pHp > 0)) {
      stop = true;
    } else {
      tx_ += it.alpha * tp_;
      tr_ -= it.alpha * tq_;
      tcg_->end(it);
      // This iteration lowered f by alpha gamma / 2 (exact for the quadratic).
      const double reg = std::max(1.0, std::abs(f_)) * std::numeric_limits<double>::epsilon();
      stop = 0.5 * it.alpha * gamma <= options_.translation_tol * std::max(step_.predicted, reg) ||
             tcg_->iterations() >= options_.translation_iterations;
    }
  }
  if (!stop) return send_translation_direction(out);
  Xt_ += tx_;
  translations_solved_ = true;
  send_public(Xt_, kTrial, out);
}

void NewtonRefineProtocol::after_translation_solve(const MessageGate::Inbox& inbox,
                                                   std::vector<OutgoingMessage>& out) {
  // The team's interface residual, blocks in id order; every agent solves the same Sigma.
  charge_to(&result_.times.translations_s);
  const Eigen::Index k = Xt_.rows();
  Eigen::MatrixXd rhat(translation_solve_->team_size(), k);
  for (const auto& [sender, m] : inbox) {
    const auto* p = std::get_if<PoseBlockMessage>(&m);
    const Eigen::Index n = translation_solve_->block_size(sender);
    if (!p || static_cast<Eigen::Index>(p->data.size()) != n * k)
      throw std::runtime_error("newton refine: malformed translation residual from agent " +
                               std::to_string(sender));
    rhat.middleRows(translation_solve_->block_offset(sender), n) =
        Eigen::Map<const Eigen::MatrixXd>(p->data.data(), n, k);
  }
  if (!translation_one_factor_)
    return take_translation_solution(translation_solve_->solve_interface(rhat), out);
  // The holder: u to every agent, flag first (0: its Sigma could not be factored).
  const bool ok = translation_solve_->ready();
  Eigen::MatrixXd u;
  if (ok) u = translation_solve_->solve_interface(rhat);
  std::vector<double> values{ok ? 1.0 : 0.0};
  values.insert(values.end(), u.data(), u.data() + u.size());
  PoseBlockMessage m =
      make_reduction_message(kSigmaHolder, message_round_, kTranslationSolution, values);
  gate_.add(kSigmaHolder, message_round_, kTranslationSolution, m);
  OutgoingMessage o;
  o.message = std::move(m);
  o.broadcast = true;
  out.push_back(std::move(o));
  gate_.expect(message_round_, kTranslationSolution, {kSigmaHolder});
  ++result_.reductions;
}

void NewtonRefineProtocol::after_translation_solution(const MessageGate::Inbox& inbox,
                                                      std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.translations_s);
  const Eigen::Index k = Xt_.rows(), team = translation_solve_->team_size();
  const auto found = inbox.find(kSigmaHolder);
  const auto* m = found == inbox.end() ? nullptr : std::get_if<PoseBlockMessage>(&found->second);
  if (!m || m->data.empty() ||
      m->data.size() != (m->data[0] != 0.0 ? static_cast<std::size_t>(1 + team * k) : 1))
    throw std::runtime_error("newton refine: malformed translation solution from agent " +
                             std::to_string(kSigmaHolder));
  ++result_.translation_solutions_received;
  if (m->data[0] == 0.0) {
    // No factor of Sigma on the holder: the block-Jacobi CG from here on, on every agent.
    translation_solve_.reset();
    translation_one_factor_ = false;
    --result_.translation_solves;
    result_.translation_interface_poses = 0;
    translation_preconditioner_ = std::make_unique<TranslationPreconditioner>(problem_);
    TranslationPreconditioner::keep_translations(problem_.dim(), tr_);
    tx_.setZero(Xt_.rows(), Xt_.cols());
    tcg_->restart();
    return send_translation_direction(out);
  }
  take_translation_solution(Eigen::Map<const Eigen::MatrixXd>(m->data.data() + 1, team, k), out);
}

void NewtonRefineProtocol::take_translation_solution(const Eigen::MatrixXd& u,
                                                     std::vector<OutgoingMessage>& out) {
  const Eigen::MatrixXd x = translation_solve_->back(ty_, u);
  // The own translations, and the neighbours' public ones from u (their own back() writes the
  // same u into them, so both copies agree to the bit).
  const int w = problem_.dim() + 1;
  for (Eigen::Index i = 0; i < x.rows(); ++i) Xt_.col(i * w + w - 1) += x.row(i).transpose();
  const std::vector<std::size_t>& nb = problem_.neighbors();
  for (std::size_t j = 0; j < nb.size(); ++j) {
    const Eigen::Index row = translation_solve_->team_row(nb[j]);
    if (row < 0) throw std::logic_error("newton refine: a neighbour pose off the interface");
    Xtn_.col(static_cast<Eigen::Index>(j) * w + w - 1) += u.row(row).transpose();
  }
  translations_solved_ = true;
  send_trial_sums(out);
}

}  // namespace tessera
