#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tessera/distributed/coarse_exchange.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/distributed/round_protocol.hpp>

#include "distributed/public_pose_messages.hpp"

namespace tessera {
namespace {

// A phase as the gate's step.
std::uint32_t step_of(ProtocolPhase phase) {
  return static_cast<std::uint32_t>(phase);
}

std::uint32_t u32(int x) {
  return static_cast<std::uint32_t>(x);
}

}  // namespace

RoundProtocol::RoundProtocol(AgentState& state, const BlockLayout& layout,
                             const RoundConfig& config)
    : state_(state), layout_(layout), config_(config) {
  config_.update.validate();
  config_.coarse.validate();
  if (config_.scheme) scheme_ = config_.scheme->clone();
  config_.scheme = nullptr;  // the clone is ours; the caller's object may go away
  if (config_.local.enabled) {
    if (config_.coarse.enabled)
      throw std::invalid_argument("RoundProtocol: local rounds do not combine with coarse ones");
    local_.emplace(layout_, config_.local, config_.grad_norm_tol);
    for (std::size_t id : state_.problem().neighbors())
      neighbour_owner_.push_back(layout_.owner[id]);
  }
}

void RoundProtocol::freeze_inactive_neighbours(Eigen::MatrixXd& copy) const {
  if (!local_) return;
  const Eigen::Index w = state_.problem().dim() + 1;
  for (std::size_t k = 0; k < neighbour_owner_.size(); ++k)
    if (!local_->active(neighbour_owner_[k]))
      copy.middleCols(w * static_cast<Eigen::Index>(k), w) =
          state_.Yn.middleCols(w * static_cast<Eigen::Index>(k), w);
}

bool RoundProtocol::selected(int block) const {
  return std::binary_search(selection_.begin(), selection_.end(), block);
}

std::vector<int> RoundProtocol::selected_neighbours() const {
  std::vector<int> out;
  for (int a : layout_.adjacent[static_cast<std::size_t>(state_.id())])
    if (selected(a)) out.push_back(a);
  return out;
}

std::vector<OutgoingMessage> RoundProtocol::start() {
  start_time_ = std::chrono::steady_clock::now();
  std::vector<OutgoingMessage> out;
  const auto& adj = layout_.adjacent[static_cast<std::size_t>(state_.id())];
  send_poses(state_.Y, BlockKind::kY, ProtocolPhase::kInit, adj, out);
  expect(0, ProtocolPhase::kInit, adj);
  pump(out);
  return out;
}

std::vector<OutgoingMessage> RoundProtocol::start_with_neighbours(
    const Eigen::MatrixXd& neighbours) {
  if (neighbours.rows() != state_.Yn.rows() || neighbours.cols() != state_.Yn.cols())
    throw std::invalid_argument("RoundProtocol: the start's neighbour poses have the wrong size");
  start_time_ = std::chrono::steady_clock::now();
  std::vector<OutgoingMessage> out;
  // What the opening exchange's messages would have written (ProtocolPhase::kInit).
  state_.Yn = neighbours;
  state_.Vn = state_.Yn;
  begin_status(ProtocolPhase::kStatus, out);
  pump(out);
  return out;
}

ProtocolSnapshot RoundProtocol::snapshot() const {
  ProtocolSnapshot s;
  s.agent = state_.id();
  s.round = round_;
  s.Y = state_.Y;
  s.P = state_.P;
  s.V = state_.V;
  s.Y_prev = state_.Y_prev;
  s.Yn = state_.Yn;
  s.Pn = state_.Pn;
  s.Vn = state_.Vn;
  s.Yn_prev = state_.Yn_prev;
  s.selection = selection_;
  s.f_prev = f_prev_;
  s.gsq_prev = gsq_prev_;
  s.restarts = restarts_;
  if (scheme_) s.scheme_state = scheme_->save();
  s.trace = trace_;
  return s;
}

std::vector<OutgoingMessage> RoundProtocol::resume(const ProtocolSnapshot& s) {
  auto fail = [&](const std::string& why) {
    throw std::runtime_error("agent " + std::to_string(state_.id()) +
                             ": cannot resume from the snapshot of round " +
                             std::to_string(s.round) + ": " + why);
  };
  if (s.agent != state_.id()) fail("it belongs to agent " + std::to_string(s.agent));
  if (local_) fail("local rounds keep no snapshot of the other blocks' statuses");
  auto same = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return a.rows() == b.rows() && a.cols() == b.cols();
  };
  for (const Eigen::MatrixXd* m : {&s.Y, &s.P, &s.V, &s.Y_prev})
    if (!same(*m, state_.Y)) fail("own block of the wrong size");
  for (const Eigen::MatrixXd* m : {&s.Yn, &s.Pn, &s.Vn, &s.Yn_prev})
    if (!same(*m, state_.Yn)) fail("neighbour copies of the wrong size");
  if (scheme_)
    scheme_->load(s.scheme_state);
  else if (!s.scheme_state.empty())
    fail("it has momentum state, this run has none");
  state_.Y = s.Y;
  state_.P = s.P;
  state_.V = s.V;
  state_.Y_prev = s.Y_prev;
  state_.Yn = s.Yn;
  state_.Pn = s.Pn;
  state_.Vn = s.Vn;
  state_.Yn_prev = s.Yn_prev;
  round_ = s.round;
  selection_ = s.selection;
  f_prev_ = s.f_prev;
  gsq_prev_ = s.gsq_prev;
  restarts_ = s.restarts;
  trace_ = s.trace;
  done_ = false;
  stop_reason_.clear();
  gate_ = MessageGate();
  const double elapsed = trace_.empty() ? 0.0 : trace_.back().elapsed_s;
  start_time_ = std::chrono::steady_clock::now() -
                std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                    std::chrono::duration<double>(elapsed));
  std::vector<OutgoingMessage> out;
  begin_status(ProtocolPhase::kStatus, out);
  pump(out);
  return out;
}

std::vector<OutgoingMessage> RoundProtocol::handle(const ProtocolMessage& message) {
  std::uint32_t round = 0, phase = 0, sender = 0;
  if (const auto* p = std::get_if<PoseBlockMessage>(&message)) {
    round = p->round, phase = p->phase, sender = p->sender;
  } else {
    const auto& s = std::get<RoundStatusMessage>(message);
    round = s.round, phase = s.phase, sender = s.sender;
  }
  if (sender >= u32(layout_.num_blocks) ||
      phase > static_cast<std::uint32_t>(ProtocolPhase::kCoarseMotions))
    throw std::runtime_error("agent " + std::to_string(state_.id()) +
                             ": malformed message (sender " + std::to_string(sender) + ", phase " +
                             std::to_string(phase) + ")");
  if (!gate_.add(static_cast<int>(sender), round, phase, message))
    throw std::runtime_error("agent " + std::to_string(state_.id()) +
                             ": duplicate message from agent " + std::to_string(sender));
  std::vector<OutgoingMessage> out;
  pump(out);
  return out;
}

void RoundProtocol::expect(std::uint32_t round, ProtocolPhase phase, std::vector<int> senders) {
  phase_ = phase;
  gate_.expect(round, step_of(phase), std::move(senders));
}

std::size_t RoundProtocol::messages_needed() const {
  if (done_) return 0;
  // pump() leaves no complete step behind, so a running protocol always waits for one.
  return std::max<std::size_t>(gate_.missing().size(), 1);
}

std::optional<AwaitedMessages> RoundProtocol::awaited() const {
  if (done_) return std::nullopt;
  AwaitedMessages a;
  a.round = gate_.round();
  a.phase = gate_.step();
  for (int s : gate_.missing()) a.senders.push_back(u32(s));
  if (a.senders.empty()) return std::nullopt;  // not after pump(); never a wait for nothing
  return a;
}

void RoundProtocol::pump(std::vector<OutgoingMessage>& out) {
  while (!done_) {
    std::optional<Inbox> taken = gate_.take_ready();
    if (!taken) return;
    complete(*taken, out);
  }
}

void RoundProtocol::send_poses(const Eigen::MatrixXd& X, BlockKind kind, ProtocolPhase phase,
                               const std::vector<int>& recipients,
                               std::vector<OutgoingMessage>& out) {
  send_public_poses(state_, X, kind, recipients, u32(round_), static_cast<std::uint32_t>(phase),
                    out);
}

void RoundProtocol::complete(Inbox& inbox, std::vector<OutgoingMessage>& out) {
  switch (phase_) {
    case ProtocolPhase::kInit:
      for (auto& [sender, m] : inbox) state_.absorb(std::get<PoseBlockMessage>(m), state_.Yn);
      state_.Vn = state_.Yn;  // V^0 = Y^0 everywhere
      begin_status(ProtocolPhase::kStatus, out);
      return;
    case ProtocolPhase::kStatus:
    case ProtocolPhase::kRedoStatus:
      after_status(phase_, inbox, out);
      return;
    case ProtocolPhase::kExtrapolate:
      throw std::logic_error("RoundProtocol: no step waits for extrapolated poses");
    case ProtocolPhase::kUpdate:
      // Unselected neighbours took P^k; selected ones overwrite it with their Y^{k+1}.
      if (scheme_ && scheme_->unselected_take_extrapolation()) state_.Yn = state_.Pn;
      for (auto& [sender, m] : inbox) state_.absorb(std::get<PoseBlockMessage>(m), state_.Yn);
      // The neighbours' V^{k+1}, exactly as each of them forms its own (same scalars, same
      // pose-wise arithmetic), from the coefficients of the round just finished; an inactive
      // one's V is its Y.
      if (scheme_) {
        momentum_update_into(state_.manifold(), coeff_, state_.Vn, state_.Pn, state_.Yn, state_.Vn);
        freeze_inactive_neighbours(state_.Vn);
      }
      ++round_;
      begin_status(ProtocolPhase::kStatus, out);
      return;
    case ProtocolPhase::kRedoUpdate:
      for (auto& [sender, m] : inbox) state_.absorb(std::get<PoseBlockMessage>(m), state_.Yn);
      state_.V = state_.Y;
      state_.Vn = state_.Yn;
      ++round_;
      begin_status(ProtocolPhase::kRedoStatus, out);
      return;
    case ProtocolPhase::kCoarseTerms:
      solve_gathered_coarse(inbox, out);
      return;
    case ProtocolPhase::kCoarseMotions:
      take_coarse_motions(inbox, out);
      return;
  }
}

void RoundProtocol::begin_status(ProtocolPhase phase, std::vector<OutgoingMessage>& out) {
  if (phase == ProtocolPhase::kStatus && observer_) observer_(snapshot());
  // Local rounds: only blocks whose status can have changed send one; the others' last one
  // stands. Otherwise every block sends.
  std::vector<int> senders;
  if (local_) {
    senders = local_->status_senders();
  } else {
    senders.resize(static_cast<std::size_t>(layout_.num_blocks));
    for (int b = 0; b < layout_.num_blocks; ++b) senders[static_cast<std::size_t>(b)] = b;
  }
  if (!local_ || local_->sends_status(state_.id())) {
    const LocalStatus s = state_.status(config_.selection == SelectionRule::kGreedyNewton);
    RoundStatusMessage m;
    m.round = u32(round_);
    m.sender = u32(state_.id());
    m.phase = static_cast<std::uint32_t>(phase);
    m.cost = s.cost_share;
    m.grad_norm_sq = s.grad_norm_sq;
    m.block_grad_norm = s.block_grad_norm;
    if (phase == ProtocolPhase::kStatus && config_.coarse.scheduled(round_)) {
      std::vector<double> terms =
          state_.coarse_space() ? state_.smoothed_coarse_terms() : state_.coarse_terms();
      if (!config_.coarse.gather) {
        m.coarse = std::move(terms);
      } else {
        // Beside the status, to the solver only (its own straight into its inbox).
        const auto step = ProtocolPhase::kCoarseTerms;
        PoseBlockMessage t = coarse_terms_message(
            state_.id(), u32(round_), static_cast<std::uint32_t>(step), std::move(terms));
        if (state_.id() == kCoarseSolver) {
          gate_.add(state_.id(), u32(round_), step_of(step), std::move(t));
        } else {
          out.push_back(addressed_to(u32(kCoarseSolver), std::move(t)));
        }
      }
    }
    // Our own status goes straight into the inbox: the reduction then treats every agent alike.
    gate_.add(state_.id(), u32(round_), step_of(phase), m);
    OutgoingMessage o;
    o.message = m;
    o.broadcast = true;
    out.push_back(std::move(o));
  }
  expect(u32(round_), phase, std::move(senders));
}

void RoundProtocol::after_status(ProtocolPhase phase, const Inbox& inbox,
                                 std::vector<OutgoingMessage>& out) {
  // The reduction: summed in agent-id order (the map's order) by every agent.
  double f = 0.0, gsq = 0.0;
  std::vector<double> norms(static_cast<std::size_t>(layout_.num_blocks), 0.0);
  if (local_) {
    for (const auto& [sender, m] : inbox) {
      const auto& s = std::get<RoundStatusMessage>(m);
      local_->record(sender, s.cost, s.grad_norm_sq, s.block_grad_norm);
    }
    local_->update_activity();
    f = local_->cost();
    gsq = local_->grad_norm_sq();
    norms = local_->scores();  // inactive blocks score 0
  } else {
    for (const auto& [sender, m] : inbox) {
      const auto& s = std::get<RoundStatusMessage>(m);
      f += s.cost;
      gsq += s.grad_norm_sq;
      norms[static_cast<std::size_t>(sender)] = s.block_grad_norm;
    }
  }
  const int me = state_.id();
  const bool restart = phase == ProtocolPhase::kStatus && scheme_ && round_ > 0 &&
                       scheme_->restart_constant() >= 0 &&
                       f_prev_ - f < scheme_->restart_constant() * gsq_prev_;
  if (restart) {
    // Back to Y^{k-1}; the same blocks redo a plain update from there. Round k's coarse
    // terms (gathered) are not used.
    gate_.discard(u32(round_), step_of(ProtocolPhase::kCoarseTerms));
    ++restarts_;
    trace_.back().restart = true;
    --round_;
    state_.Y = state_.Y_prev;
    state_.Yn = state_.Yn_prev;
    scheme_->restart();
    if (selected(me)) {
      state_.Y = state_.update(state_.Y, state_.Yn, config_.update);
      send_poses(state_.Y, BlockKind::kY, ProtocolPhase::kRedoUpdate,
                 layout_.adjacent[static_cast<std::size_t>(me)], out);
    }
    expect(u32(round_), ProtocolPhase::kRedoUpdate, selected_neighbours());
    return;
  }
  RoundRecord rec;
  rec.round = round_;
  rec.cost = f;
  rec.grad_norm = std::sqrt(gsq);
  rec.elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time_).count();
  const bool small_decrease = config_.rel_cost_decrease_tol > 0 && round_ > 0 && f <= f_prev_ &&
                              f_prev_ - f <= config_.rel_cost_decrease_tol * std::abs(f);
  if (rec.grad_norm <= config_.grad_norm_tol)
    stop_reason_ = "grad_norm";
  else if (round_ >= config_.max_rounds)
    stop_reason_ = "max_rounds";
  else if (stalled(rec))
    stop_reason_ = "stalled";
  else if (small_decrease)
    stop_reason_ = "relative_decrease";
  if (!stop_reason_.empty()) {
    trace_.push_back(rec);
    done_ = true;
    return;
  }
  // The coarse correction moves Y^k before the block updates; f moves by exactly the coarse
  // cost's change, so the next restart test compares against the corrected cost.
  if (phase == ProtocolPhase::kStatus && config_.coarse.scheduled(round_)) {
    if (config_.coarse.gather) {
      held_ = {rec, f, gsq, norms};
      if (me == kCoarseSolver) {
        std::vector<int> all(static_cast<std::size_t>(layout_.num_blocks));
        for (int b = 0; b < layout_.num_blocks; ++b) all[static_cast<std::size_t>(b)] = b;
        expect(u32(round_), ProtocolPhase::kCoarseTerms, std::move(all));
      } else {
        expect(u32(round_), ProtocolPhase::kCoarseMotions, {kCoarseSolver});
      }
      return;
    }
    f += coarse_correct(inbox, round_ > 0 ? f_prev_ - f : 0.0);
  }
  continue_round(rec, f, gsq, norms, out);
}

void RoundProtocol::continue_round(RoundRecord rec, double f, double gsq,
                                   const std::vector<double>& norms,
                                   std::vector<OutgoingMessage>& out) {
  const int me = state_.id();
  f_prev_ = f;
  gsq_prev_ = gsq;
  const ClassScore class_score = scheme_ ? scheme_->class_score() : ClassScore::kLargestBlock;
  selection_ = select_blocks(config_.selection, config_.parallel, config_.seed,
                             static_cast<std::uint64_t>(round_), norms, layout_, class_score);
  // A block that did not move since the last round still holds Y^{k-1} in Y_prev.
  const bool keep_prev = !local_ || local_->moved(me);
  if (local_) select_local(class_score, norms);
  rec.selected = selection_;
  trace_.push_back(rec);
  if (keep_prev) state_.Y_prev = state_.Y;
  state_.Yn_prev = state_.Yn;
  if (!scheme_) {
    begin_update(out);
    return;
  }
  coeff_ = scheme_->coefficients();
  // P^k needs no exchange: the neighbours' public P^k is formed from their mirrored V^k.
  if (active_self()) extrapolate_into(state_.manifold(), coeff_, state_.Y, state_.V, state_.P);
  extrapolate_into(state_.manifold(), coeff_, state_.Yn, state_.Vn, state_.Pn);
  freeze_inactive_neighbours(state_.Pn);
  begin_update(out);
}

void RoundProtocol::select_local(ClassScore class_score, const std::vector<double>& scores) {
  auto keep_active = [&] {
    selection_.erase(std::remove_if(selection_.begin(), selection_.end(),
                                    [&](int b) { return !local_->active(b); }),
                     selection_.end());
  };
  keep_active();
  // Uniform or round-robin may draw a unit with no active block: take the greedy one instead
  // (scores are 0 for inactive blocks), so every round moves some block that has work.
  if (selection_.empty()) {
    selection_ = select_blocks(SelectionRule::kGreedy, config_.parallel, config_.seed,
                               static_cast<std::uint64_t>(round_), scores, layout_, class_score);
    keep_active();
  }
  std::vector<int> movers = selection_;
  if (scheme_ && scheme_->unselected_take_extrapolation())
    for (int b = 0; b < layout_.num_blocks; ++b)
      if (local_->active(b) && !selected(b)) movers.push_back(b);
  local_->set_moved(movers);
}

double RoundProtocol::coarse_correct(const Inbox& inbox, double last_decrease) {
  std::vector<const std::vector<double>*> terms;
  terms.reserve(inbox.size());
  for (const auto& [sender, m] : inbox) terms.push_back(&std::get<RoundStatusMessage>(m).coarse);
  const CoarseResult c = solve_coarse_terms(terms);
  if (!c.moved || c.cost_before - c.cost_after < config_.coarse.min_gain * last_decrease)
    return 0.0;
  apply_coarse_motions(c.motions, c.cost_before - c.cost_after);
  return c.cost_after - c.cost_before;
}

CoarseResult RoundProtocol::solve_coarse_terms(
    const std::vector<const std::vector<double>*>& terms) const {
  const CoarseSpace* space = state_.coarse_space();
  return space ? solve_smoothed_coarse(*space, state_.rank(), terms, config_.coarse)
               : solve_coarse(layout_, state_.rank(), terms, config_.coarse);
}

void RoundProtocol::apply_coarse_motions(const std::vector<Eigen::MatrixXd>& motions,
                                         double decrease) {
  // The smoothed space's blend is put back on the manifold afterwards, so its f moves by the
  // coarse decrease to second order in the step (coarse_space.hpp).
  if (state_.coarse_space())
    state_.apply_smoothed_coarse(motions);
  else
    state_.apply_coarse(motions);
  ++coarse_corrections_;
  coarse_decrease_ += decrease;
}

const std::vector<int>& RoundProtocol::coarse_unknowns(int agent) {
  if (coarse_unknowns_.empty())
    coarse_unknowns_.resize(static_cast<std::size_t>(layout_.num_blocks));
  auto& u = coarse_unknowns_[static_cast<std::size_t>(agent)];
  if (u.empty()) u = coarse_unknowns_of(state_.coarse_space(), layout_, agent);
  return u;
}

void RoundProtocol::solve_gathered_coarse(const Inbox& inbox, std::vector<OutgoingMessage>& out) {
  std::vector<const std::vector<double>*> terms;
  terms.reserve(inbox.size());
  for (const auto& [sender, m] : inbox) terms.push_back(&coarse_terms_of(m));
  const double last_decrease = round_ > 0 ? f_prev_ - held_.f : 0.0;
  const CoarseResult c = solve_coarse_terms(terms);
  const bool applied =
      c.moved && c.cost_before - c.cost_after >= config_.coarse.min_gain * last_decrease;
  const double decrease = c.cost_before - c.cost_after;
  for (int a = 0; a < layout_.num_blocks; ++a) {
    if (a == state_.id()) continue;
    out.push_back(addressed_to(
        u32(a), coarse_motions_message(state_.id(), u32(round_),
                                       static_cast<std::uint32_t>(ProtocolPhase::kCoarseMotions),
                                       coarse_unknowns(a), c.motions, decrease, applied)));
  }
  double f = held_.f;
  if (applied) {
    apply_coarse_motions(c.motions, decrease);
    f -= decrease;
  }
  continue_round(held_.rec, f, held_.gsq, held_.norms, out);
}

void RoundProtocol::take_coarse_motions(const Inbox& inbox, std::vector<OutgoingMessage>& out) {
  const CoarseSpace* space = state_.coarse_space();
  const int count = space ? space->num_aggregates : layout_.num_blocks;
  const ReceivedCoarseMotions c = read_coarse_motions(inbox.at(kCoarseSolver), state_.rank(), count,
                                                      coarse_unknowns(state_.id()));
  double f = held_.f;
  if (c.applied) {
    apply_coarse_motions(c.motions, c.decrease);
    f -= c.decrease;
  }
  continue_round(held_.rec, f, held_.gsq, held_.norms, out);
}

bool RoundProtocol::stalled(const RoundRecord& rec) const {
  // Near the optimum every block update can be rejected: the trust region cannot measure a
  // decrease of the block's cost below its round-off (solvers/trust_region.cpp), so no block
  // moves and the cost and gradient norm repeat bit for bit, round after round (seen at
  // ||grad f|| ~ 1e-5 on a 500-pose grid, ~1e-4 after a re-partition for survivors). A
  // tolerance below that floor would otherwise spin to max_rounds (10000 rounds, minutes).
  // Enough rounds that every block had its turn many times (parallel colour classes, uniform
  // selection). Computed from the trace, which snapshots restore, so a resumed run stops at
  // the same round as an uninterrupted one.
  const std::size_t window = static_cast<std::size_t>(std::max(20, 10 * layout_.num_blocks));
  if (trace_.size() < window) return false;
  for (std::size_t i = trace_.size() - window; i < trace_.size(); ++i)
    if (trace_[i].cost != rec.cost || trace_[i].grad_norm != rec.grad_norm) return false;
  return true;
}

void RoundProtocol::begin_update(std::vector<OutgoingMessage>& out) {
  const int me = state_.id();
  const bool accelerated = scheme_ != nullptr;
  Eigen::MatrixXd Y_new;
  if (selected(me)) {
    Y_new = accelerated ? state_.update(state_.P, state_.Pn, config_.update)
                        : state_.update(state_.Y, state_.Yn, config_.update);
    send_poses(Y_new, BlockKind::kY, ProtocolPhase::kUpdate,
               layout_.adjacent[static_cast<std::size_t>(me)], out);
  } else if (!active_self()) {
    // Inactive: Y stays, and V := Y so that the momentum starts afresh when the block wakes
    // up (its neighbours' copies do the same).
    if (accelerated) {
      if (!frozen_) state_.V = state_.Y;
      frozen_ = true;
      scheme_->advance();
    }
    expect(u32(round_), ProtocolPhase::kUpdate, selected_neighbours());
    return;
  } else {
    Y_new = (accelerated && scheme_->unselected_take_extrapolation()) ? state_.P : state_.Y;
  }
  if (accelerated) {
    momentum_update_into(state_.manifold(), coeff_, state_.V, state_.P, Y_new, state_.V);
    scheme_->advance();
    frozen_ = false;
  }
  state_.Y = std::move(Y_new);
  expect(u32(round_), ProtocolPhase::kUpdate, selected_neighbours());
}

}  // namespace tessera
