#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/util/input_error.hpp>

#include "distributed/interface_solve.hpp"
#include "distributed/rounds_tail.hpp"

namespace tessera {

void StaircaseOptions::validate() const {
  if (max_rank < 2) throw InputError("StaircaseOptions.max_rank must be >= d (2 or 3)");
  if (!(grad_norm_tol >= 0)) throw InputError("StaircaseOptions.grad_norm_tol must be >= 0");
  certificate.validate();
  escape.validate();
}

CertifiedAgent::CertifiedAgent(AgentState& state, const BlockLayout& layout,
                               const DistributedOptions& options)
    : state_(state), layout_(layout), options_(options) {
  // The layout is the same on every agent, so is this decision (as the refinement's own).
  interface_fits_ = interface_fits(options_.refine, layout_, state_.problem().dim());
}

bool CertifiedAgent::hands_over_early() const {
  // Not conditioned on the rank: the refinement works on the iterate's active rows, d of them
  // where the relaxation is tight, whatever the lifted rank.
  return interface_fits_;
}

double CertifiedAgent::solve_tolerance() const {
  // An inconclusive certificate's refinement is the Newton refinement's where it is on: the
  // rounds stop at once (the point is at the solver's tolerance already) and hand over.
  if (refining_ && !options_.refine.enabled) return refine_tolerance();
  if (hands_over_early())
    return std::max(options_.grad_norm_tol, options_.refine.auto_interface_grad_tol);
  return options_.grad_norm_tol;
}

bool CertifiedAgent::refine_wanted(const std::vector<RoundRecord>& trace) const {
  if (options_.refine.when == NewtonRefineOptions::When::kAlways) return true;
  if (refining_) return true;  // after an inconclusive certificate (solve_tolerance)
  if (hands_over_early()) return true;
  return rounds_tail_gap(trace, options_.refine.auto_window, 0.9) > options_.refine.auto_gap_tol;
}

double CertifiedAgent::refine_tolerance() const {
  if (options_.certify && options_.staircase.grad_norm_tol > 0)
    return std::min(options_.grad_norm_tol, options_.staircase.grad_norm_tol);
  return options_.grad_norm_tol;
}

std::optional<bool> CertifiedAgent::certified() const {
  if (!options_.certify) return std::nullopt;
  if (certificates_.empty() || solves_.empty()) return false;
  const std::string& stop = solves_.back().stop_reason;
  // "stalled": as close to a critical point as the block updates can resolve.
  const bool converged = stop == "grad_norm" || stop == "relative_decrease" || stop == "stalled";
  // The last certificate must be of the last solve (an escape that failed leaves it so).
  return converged && certificates_.back().rank == solves_.back().rank &&
         certificates_.back().result.certified;
}

int CertifiedAgent::total_rounds() const {
  int n = 0;
  for (const auto& s : solves_) n += s.rounds;
  return n;
}
int CertifiedAgent::total_restarts() const {
  int n = 0;
  for (const auto& s : solves_) n += s.restarts;
  return n;
}
int CertifiedAgent::certificate_iterations() const {
  int n = 0;
  for (const auto& c : certificates_) n += c.result.iterations;
  return n;
}
int CertifiedAgent::escape_trials() const {
  int n = 0;
  for (const auto& e : escapes_) n += e.trials;
  return n;
}

void CertifiedAgent::emit(std::vector<OutgoingMessage>&& sub,
                          std::vector<OutgoingMessage>& out) const {
  for (auto& o : sub) {
    std::visit([&](auto& m) { m.phase = tag_phase(stage_, m.phase); }, o.message);
    out.push_back(std::move(o));
  }
}

std::vector<OutgoingMessage> CertifiedAgent::start() {
  if (known_grad_norm_ && can_start_at_refinement()) return start_at_refinement();
  std::vector<OutgoingMessage> out;
  begin(0, out);
  advance(out);
  return out;
}

std::vector<OutgoingMessage> CertifiedAgent::start_with_neighbours(
    const Eigen::MatrixXd& neighbours) {
  start_neighbours_ = neighbours;
  std::vector<OutgoingMessage> out;
  begin(0, out);
  advance(out);
  return out;
}

bool CertifiedAgent::can_start_at_refinement() const {
  // Such rounds stop at their round-0 status ("grad_norm") and refine_wanted() holds there. A
  // certificate follows the refinement as it follows the rounds.
  if (!options_.refine.enabled) return false;
  const bool refined =
      hands_over_early() || options_.refine.when == NewtonRefineOptions::When::kAlways;
  const double tol = solve_tolerance();
  const bool stops_at_start =
      std::isinf(tol) || (known_grad_norm_ && *known_grad_norm_ <= 0.5 * tol);
  return refined && stops_at_start;
}

std::vector<OutgoingMessage> CertifiedAgent::start_at_refinement() {
  if (!can_start_at_refinement())
    throw std::logic_error("CertifiedAgent: this solve does not start at its refinement");
  std::vector<OutgoingMessage> out;
  stage_ = 0;
  solves_.push_back(
      {stage_, state_.rank(), 0, 0, "grad_norm", {}, solve_tolerance(), refining_, false});
  begin_refine(out);
  advance(out);
  return out;
}

void CertifiedAgent::begin_refine(std::vector<OutgoingMessage>& out) {
  NewtonRefineOptions refine = options_.refine;
  // Handed over early, the refinement also owes the rounds' own tolerance where that is the
  // tighter one.
  if (hands_over_early() && options_.grad_norm_tol > 0)
    refine.grad_norm_tol = std::min(refine.grad_norm_tol, options_.grad_norm_tol);
  refine_ = std::make_unique<NewtonRefineProtocol>(state_, layout_, refine);
  if (trial_observer_) refine_->set_trial_observer(trial_observer_);
  if (!solves_.empty() && !solves_.back().trace.empty())
    refine_->set_start_grad_norm(solves_.back().trace.back().grad_norm);
  else if (known_grad_norm_ && stage_ == 0)
    refine_->set_start_grad_norm(*known_grad_norm_);
  current_ = refine_.get();
  emit(refine_->start(), out);
  for (const ProtocolMessage& m :
       kept_.take_steps(tag_phase(stage_, NewtonRefineProtocol::kStatus),
                        tag_phase(stage_, NewtonRefineProtocol::kLastStep) + 1)) {
    if (current_->done()) break;
    to_current(m, out);
  }
}

std::vector<OutgoingMessage> CertifiedAgent::resume(const ProtocolSnapshot& snapshot) {
  std::vector<OutgoingMessage> out;
  begin(0, out, &snapshot);
  advance(out);
  return out;
}

void CertifiedAgent::begin(std::uint32_t stage, std::vector<OutgoingMessage>& out,
                           const ProtocolSnapshot* resume_from) {
  stage_ = stage;
  switch (stage_kind(stage)) {
    case StageKind::kSolve: {
      DistributedOptions o = options_;
      o.rank = state_.rank();
      o.grad_norm_tol = solve_tolerance();
      const double variables = static_cast<double>(state_.rank()) * (state_.problem().dim() + 1) *
                               static_cast<double>(layout_.owner.size());
      const auto scheme = make_momentum_scheme(o, layout_, variables);
      solve_ = std::make_unique<RoundProtocol>(state_, layout_, make_round_config(o, scheme.get()));
      if (stage == 0 && observer_) solve_->set_round_observer(observer_);
      current_ = solve_.get();
      if (resume_from) {
        emit(solve_->resume(*resume_from), out);
        return;  // nothing of a later stage can be pending yet
      }
      break;
    }
    case StageKind::kCertify: {
      DistributedCertificateOptions c = options_.staircase.certificate;
      c.seed = options_.seed;
      state_.release_block_factor();  // not needed until the next solve stage, if any
      certify_ = std::make_unique<CertificateProtocol>(state_, layout_, c);
      current_ = certify_.get();
      break;
    }
    case StageKind::kEscape:
      escape_ = std::make_unique<SaddleEscapeProtocol>(
          state_, layout_, direction_, solves_.back().trace.back().cost,
          options_.grad_norm_tol,  // the next rank's solve starts at the solver's tolerance
          options_.staircase.escape);
      current_ = escape_.get();
      break;
  }
  if (solve_ && current_ == solve_.get() && start_neighbours_.size() > 0) {
    emit(solve_->start_with_neighbours(start_neighbours_), out);
    start_neighbours_.resize(0, 0);
  } else {
    emit(current_->start(), out);
  }
  // Messages of this stage that arrived while we were still in an earlier one.
  for (const ProtocolMessage& m : kept_.take_steps(tag_phase(stage, 0), tag_phase(stage + 1, 0))) {
    if (current_->done()) break;
    dispatch(m, out);
  }
}

void CertifiedAgent::keep(const ProtocolMessage& message) {
  // Keyed as the stage protocols' own gates key it (round, step, sender), so a second copy is
  // refused here as it would be there.
  const std::uint32_t sender = message_sender(message);
  if (!kept_.add(static_cast<int>(sender), message_round(message), message_phase(message), message))
    throw std::runtime_error("agent " + std::to_string(state_.id()) +
                             ": duplicate message from agent " + std::to_string(sender));
}

void CertifiedAgent::to_current(const ProtocolMessage& message, std::vector<OutgoingMessage>& out) {
  ProtocolMessage m = message;
  std::visit([](auto& x) { x.phase = step_of_phase(x.phase); }, m);
  emit(current_->handle(m), out);
}

void CertifiedAgent::dispatch(const ProtocolMessage& message, std::vector<OutgoingMessage>& out) {
  const bool refine_step =
      NewtonRefineProtocol::is_refine_step(step_of_phase(message_phase(message)));
  if (stage_kind(stage_) == StageKind::kSolve && current_ != refine_.get() && refine_step) {
    keep(message);  // until this stage's refinement begins
    return;
  }
  // The finished rounds' stragglers are of no use to the refinement.
  if (refine_ && current_ == refine_.get() && !refine_step) return;
  to_current(message, out);
}

std::size_t CertifiedAgent::messages_needed() const {
  if (done_) return 0;
  return current_ ? std::max<std::size_t>(current_->messages_needed(), 1) : 1;
}

std::optional<AwaitedMessages> CertifiedAgent::awaited() const {
  if (done_ || !current_) return std::nullopt;
  std::optional<AwaitedMessages> a = current_->awaited();
  if (a) a->phase = tag_phase(stage_, a->phase);
  return a;
}

std::vector<OutgoingMessage> CertifiedAgent::handle(const ProtocolMessage& message) {
  std::vector<OutgoingMessage> out;
  if (done_) return out;
  const std::uint32_t stage = stage_of_phase(message_phase(message));
  if (stage < stage_) return out;  // a finished stage needs nothing more
  if (stage > stage_) {
    if (stage > stage_ + 3 * 64)
      throw std::runtime_error("agent " + std::to_string(state_.id()) +
                               ": message of an impossible stage " + std::to_string(stage));
    keep(message);
    return out;
  }
  dispatch(message, out);
  advance(out);
  return out;
}

void CertifiedAgent::advance(std::vector<OutgoingMessage>& out) {
  while (!done_ && current_->done()) {
    const int rank = state_.rank();
    switch (stage_kind(stage_)) {
      case StageKind::kSolve: {
        if (!refine_) {  // the block-coordinate rounds just ended
          solves_.push_back({stage_, rank, solve_->rounds(), solve_->restarts(),
                             solve_->stop_reason(), solve_->trace().to_vector(), solve_tolerance(),
                             refining_});
          const std::string& stop = solves_.back().stop_reason;
          // A solve out of rounds is not refined: max_rounds is the run's budget.
          if (options_.refine.enabled && !solves_.back().trace.empty() &&
              (stop == "grad_norm" || stop == "relative_decrease" || stop == "stalled") &&
              refine_wanted(solves_.back().trace)) {
            begin_refine(out);
            continue;
          }
        } else {
          // The refinement's point ends the stage's trace, so the cost and gradient reported
          // (and the escape's reference cost) are the refined ones.
          const NewtonRefineResult& r = refine_->result();
          refines_.push_back(r);
          // Started at the refinement, the stage has no round record to copy: its point is the
          // refinement's (moved or not), which the certificate and the escape start from.
          const bool started_here = !solve_;
          if (r.accepted_steps > 0 || (started_here && solves_.back().trace.empty())) {
            RoundRecord last =
                solves_.back().trace.empty() ? RoundRecord{} : solves_.back().trace.back();
            last.cost = r.cost;
            last.grad_norm = r.grad_norm;
            last.selected.clear();
            last.restart = false;
            solves_.back().trace.push_back(std::move(last));
          }
          refine_.reset();
          current_ = solve_.get();
        }
        const bool no_point = solve_ ? solve_->trace().empty() : solves_.back().trace.empty();
        if (!options_.certify || no_point) {
          done_ = true;
          break;
        }
        begin(stage_ + 1, out);
        break;
      }
      case StageKind::kCertify: {
        CertifyStageRecord rec{stage_, rank, certify_->result()};
        direction_ = std::move(rec.result.eigenvector);
        rec.result.eigenvector.resize(0, 0);
        const bool negative = rec.result.min_eigenvalue < -rec.result.tolerance;
        certificates_.push_back(std::move(rec));
        certify_.reset();
        if (certificates_.back().result.certified) {
          done_ = true;
          break;
        }
        // The solve ran out of rounds (max_rounds is the run's budget): refining or escaping
        // would spend rounds past it, from a point that is not stationary. The certificate's
        // minimum eigenvalue is then the reported gap.
        if (!solves_.empty() && solves_.back().stop_reason == "max_rounds") {
          done_ = true;
          break;
        }
        // Not certified at the solver's tolerance: Lambda(X) may be off by the residual
        // gradient, so the verdict is inconclusive. Refine the same rank to the tighter
        // tolerance (the next solve stage, skipping the escape) and certify again.
        if (!refining_ && refine_tolerance() < options_.grad_norm_tol) {
          refining_ = true;
          begin(stage_ + 2, out);
          break;
        }
        if (!negative || rank >= options_.staircase.max_rank) {
          done_ = true;
          break;
        }
        begin(stage_ + 1, out);
        break;
      }
      case StageKind::kEscape: {
        const SaddleEscapeResult& r = escape_->result();
        escapes_.push_back({stage_, rank, r.success, r.trials, r.alpha, r.cost});
        if (!r.success) {
          done_ = true;
          break;
        }
        state_.reset_iterate(r.Y, r.Yn);
        escape_.reset();
        refining_ = false;  // the new rank starts at the solver's tolerance again
        begin(stage_ + 1, out);
        break;
      }
    }
  }
}

}  // namespace tessera
