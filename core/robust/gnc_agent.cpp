#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

namespace {

std::uint32_t phase_of(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.phase; }, m);
}
std::uint32_t sender_of(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.sender; }, m);
}

}  // namespace

GncAgent::GncAgent(GncAgentInput input, const GncDistributedOptions& options, bool final_solve)
    : in_(std::move(input)), options_(options), final_solve_wanted_(final_solve) {
  options_.validate();
  const std::size_t m = in_.measurements.size();
  if (in_.measurement_index.size() != m)
    throw std::invalid_argument("GncAgent: one file position per measurement expected");
  if (!in_.known_inlier.empty() && in_.known_inlier.size() != m)
    throw std::invalid_argument("GncAgent: one known-inlier flag per measurement expected");
  if (!std::is_sorted(in_.measurement_index.begin(), in_.measurement_index.end()))
    throw std::invalid_argument("GncAgent: measurements must be in file order");
  if (options_.robust.max_outer_iterations + 2 > static_cast<int>(kMaxGncSteps))
    throw InputError("RobustOptions.max_outer_iterations must be <= " +
                     std::to_string(kMaxGncSteps - 2) + " for the distributed solve");
  layout_ =
      std::make_unique<BlockLayout>(make_block_layout(in_.num_poses, in_.structure, in_.owner));
  weights_.assign(m, 1.0);
  for (std::size_t k = 0; k < m; ++k)
    if (weight_owner(in_.measurements[k], in_.owner) == in_.id) owned_.push_back(k);
}

GncAgent::~GncAgent() = default;

int GncAgent::total_rounds() const {
  return gnc_rounds_ + final_rounds_;
}

bool GncAgent::may_reject(std::size_t k) const {
  return !is_known_inlier(in_.measurements[k], options_.robust.known_inliers) &&
         (in_.known_inlier.empty() || !in_.known_inlier[k]);
}

// The measurement's term of the relaxed objective at the current lifted iterate: the own
// block's columns and the neighbours' public poses just received.
double GncAgent::residual_squared_at(std::size_t k) const {
  const Measurement& m = in_.measurements[k];
  const Eigen::Index w = in_.d + 1;
  const auto& own = layout_->poses[static_cast<std::size_t>(in_.id)];
  const auto& nb = state_->problem().neighbors();
  auto block = [&](std::size_t p) -> Eigen::MatrixXd {
    if (in_.owner[p] == in_.id) {
      const auto s = std::lower_bound(own.begin(), own.end(), p) - own.begin();
      return state_->Y.middleCols(w * s, w);
    }
    const auto s = std::lower_bound(nb.begin(), nb.end(), p) - nb.begin();
    return neighbours_.middleCols(w * s, w);
  };
  return lifted_residual_squared(m, block(m.i), block(m.j));
}

void GncAgent::weights_at_mu(double mu) {
  for (std::size_t k : owned_)
    if (may_reject(k)) weights_[k] = tls_weight(residual_squared_at(k), c2_, mu);
}

std::vector<OutgoingMessage> GncAgent::start() {
  std::vector<OutgoingMessage> out;
  begin_solve(out);
  return out;
}

void GncAgent::begin_solve(std::vector<OutgoingMessage>& out) {
  step_ = Step::kSolve;
  solve_.reset();
  solve_options_ = options_.solver;
  std::vector<Measurement> measurements;
  if (final_solve_) {
    measurements = kept_;
  } else {
    solve_options_.certify = false;
    measurements = in_.measurements;
    if (g_ > 0) {
      // The weighted solves between weight updates need only a rough minimiser.
      if (options_.robust.inner_max_rounds > 0)
        solve_options_.max_rounds =
            std::min(solve_options_.max_rounds, options_.robust.inner_max_rounds);
      for (std::size_t k = 0; k < measurements.size(); ++k) {
        const double w = std::max(weights_[k], kMinInnerWeight);
        measurements[k].kappa *= w;
        measurements[k].tau *= w;
      }
    }
  }
  const Eigen::MatrixXd Y = state_ ? state_->Y : in_.Y0;
  state_ = std::make_unique<AgentState>(in_.id, in_.d, *layout_, measurements, Y,
                                        solve_options_.block_update);
  solve_ = std::make_unique<CertifiedAgent>(*state_, *layout_, solve_options_);
  std::vector<OutgoingMessage> first = solve_->start();
  for (auto& o : first) {
    std::visit([&](auto& x) { x.phase += g_ * kGncStepStride; }, o.message);
    out.push_back(std::move(o));
  }
  const std::uint32_t g = g_;
  replay(out);
  if (!done_ && g_ == g && step_ == Step::kSolve && solve_->done()) after_solve(out);
}

bool GncAgent::in_current_solve(std::uint32_t phase) const {
  return phase >= g_ * kGncStepStride && phase < g_ * kGncStepStride + kGncExchangeBase;
}

std::uint32_t GncAgent::exchange_phase() const {
  switch (step_) {
    case Step::kPoses:
      return gnc_phase(g_, GncExchange::kPoses);
    case Step::kVotes:
      return gnc_phase(g_, GncExchange::kVotes);
    case Step::kWeights:
      return gnc_phase(g_, GncExchange::kWeights);
    case Step::kRejected:
      return gnc_phase(g_, GncExchange::kRejected);
    default:
      return 0;
  }
}

void GncAgent::begin_exchange(Step step, std::vector<OutgoingMessage>& out) {
  step_ = step;
  const std::uint32_t phase = exchange_phase();
  const auto me = static_cast<std::uint32_t>(in_.id);
  waiting_.clear();
  votes_.clear();
  auto to_others = [&](RoundStatusMessage st, bool broadcast,
                       const std::function<void(std::uint32_t, RoundStatusMessage&)>& fill) {
    st.phase = phase;
    st.sender = me;
    for (std::uint32_t a = 0; a < static_cast<std::uint32_t>(in_.num_agents); ++a)
      if (a != me) waiting_.push_back(a);
    if (broadcast) {
      if (!waiting_.empty()) out.push_back(OutgoingMessage{st, true, {}});
      return;
    }
    for (std::uint32_t a : waiting_) {
      RoundStatusMessage s = st;
      fill(a, s);
      out.push_back(OutgoingMessage{std::move(s), false, {a}});
    }
  };
  switch (step) {
    case Step::kPoses: {
      // Weights are computed at the iterate itself: the owners' public poses, sent once.
      const auto& nb = state_->problem().neighbors();
      neighbours_ = Eigen::MatrixXd::Zero(state_->Y.rows(),
                                          (in_.d + 1) * static_cast<Eigen::Index>(nb.size()));
      for (int b : layout_->adjacent[static_cast<std::size_t>(in_.id)]) {
        out.push_back(OutgoingMessage{state_->publish(state_->Y, BlockKind::kY, b, 0, phase),
                                      false,
                                      {static_cast<std::uint32_t>(b)}});
        waiting_.push_back(static_cast<std::uint32_t>(b));
      }
      break;
    }
    case Step::kVotes: {
      // mu's start needs the largest residual; c^2's default needs how many may be rejected.
      double max_r2 = 0;
      double candidates = 0;
      for (std::size_t k : owned_)
        if (may_reject(k)) {
          max_r2 = std::max(max_r2, residual_squared_at(k));
          candidates += 1;
        }
      votes_[me] = {max_r2, candidates};
      RoundStatusMessage st;
      st.cost = max_r2;
      st.grad_norm_sq = candidates;
      to_others(st, true, nullptr);
      break;
    }
    case Step::kWeights: {
      weights_at_mu(mu_);
      double spread = 0;
      for (std::size_t k : owned_) spread += weights_[k] * (1 - weights_[k]);
      votes_[me] = {spread, 0};
      RoundStatusMessage st;
      st.grad_norm_sq = spread;
      to_others(st, false, [&](std::uint32_t a, RoundStatusMessage& s) {
        // The cut measurements this agent weighs whose other end `a` holds.
        for (std::size_t k : owned_) {
          const Measurement& m = in_.measurements[k];
          if (static_cast<std::uint32_t>(in_.owner[std::max(m.i, m.j)]) != a) continue;
          s.measurement_ids.push_back(in_.measurement_index[k]);
          s.weights.push_back(weights_[k]);
        }
      });
      break;
    }
    case Step::kRejected: {
      rejected_.clear();
      for (std::size_t k : owned_)
        if (weights_[k] < 0.5) rejected_.push_back(in_.measurement_index[k]);
      RoundStatusMessage st;
      st.measurement_ids = rejected_;
      to_others(st, true, nullptr);
      break;
    }
    default:
      break;
  }
  replay(out);
  if (!done_ && step_ == step && exchange_phase() == phase && waiting_.empty()) after_exchange(out);
}

void GncAgent::after_solve(std::vector<OutgoingMessage>& out) {
  if (final_solve_) {
    final_rounds_ += solve_->total_rounds();
    done_ = true;
    step_ = Step::kDone;
    return;
  }
  gnc_rounds_ += solve_->total_rounds();
  if (g_ > 0 && (converged_ || outer_ >= options_.robust.max_outer_iterations)) {
    begin_exchange(Step::kRejected, out);
    return;
  }
  begin_exchange(Step::kPoses, out);
}

void GncAgent::after_exchange(std::vector<OutgoingMessage>& out) {
  switch (step_) {
    case Step::kPoses:
      begin_exchange(voted_ ? Step::kWeights : Step::kVotes, out);
      return;
    case Step::kVotes: {
      voted_ = true;
      double max_r2 = 0, candidates = 0;
      for (const auto& [sender, v] : votes_) {  // agent-id order
        max_r2 = std::max(max_r2, v.first);
        candidates += v.second;
      }
      c2_ = tls_threshold_squared(options_.robust, in_.d, static_cast<std::size_t>(candidates));
      mu_ = gnc_initial_mu(max_r2, c2_);
      converged_ = mu_ == 0;
      begin_exchange(converged_ ? Step::kRejected : Step::kWeights, out);
      return;
    }
    case Step::kWeights: {
      double spread = 0;
      for (const auto& [sender, v] : votes_) spread += v.first;  // agent-id order
      ++outer_;
      if (weight_observer_) weight_observer_(outer_, in_.measurement_index, weights_);
      converged_ = spread <= options_.robust.weight_tolerance;
      mu_ *= options_.robust.mu_step;
      ++g_;
      begin_solve(out);
      return;
    }
    case Step::kRejected: {
      std::sort(rejected_.begin(), rejected_.end());
      // The kept set must connect every pose (every agent checks the same set).
      PoseGraph kept_structure;
      kept_structure.d = in_.d;
      kept_structure.num_poses = in_.num_poses;
      std::size_t next = 0;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> kept_endpoints;
      for (std::size_t e = 0; e < in_.structure.size(); ++e) {
        if (next < rejected_.size() && rejected_[next] == e) {
          ++next;
          continue;
        }
        kept_endpoints.push_back(in_.structure[e]);
        Measurement m;
        m.i = in_.structure[e].first;
        m.j = in_.structure[e].second;
        kept_structure.measurements.push_back(std::move(m));
      }
      const std::size_t parts = count_components(kept_structure);
      if (parts > 1)
        throw InputError(
            "robust solve: " + std::to_string(rejected_.size()) + " of " +
            std::to_string(in_.structure.size()) +
            " measurements look like outliers, and the kept ones split the poses into " +
            std::to_string(parts) +
            " unconnected parts, so no estimate is defined (too few consistent measurements; "
            "try --known-inliers odometry or a larger --inlier-threshold)");
      kept_.clear();
      kept_index_.clear();
      for (std::size_t k = 0; k < in_.measurements.size(); ++k)
        if (!std::binary_search(rejected_.begin(), rejected_.end(), in_.measurement_index[k])) {
          kept_.push_back(in_.measurements[k]);
          kept_index_.push_back(in_.measurement_index[k]);
        }
      if (!final_solve_wanted_) {
        done_ = true;
        step_ = Step::kDone;
        return;
      }
      // The kept set's layout (a rejected cut measurement may end a neighbourhood); the
      // state keeps the iterate.
      auto layout = std::make_unique<BlockLayout>(
          make_block_layout(in_.num_poses, kept_endpoints, in_.owner));
      const Eigen::MatrixXd Y = state_->Y;
      solve_.reset();
      state_.reset();
      layout_ = std::move(layout);
      in_.Y0 = Y;
      final_solve_ = true;
      ++g_;
      begin_solve(out);
      return;
    }
    default:
      return;
  }
}

void GncAgent::feed(const ProtocolMessage& message, std::vector<OutgoingMessage>& out) {
  const std::uint32_t phase = phase_of(message);
  if (step_ == Step::kSolve) {
    ProtocolMessage m = message;
    std::visit([&](auto& x) { x.phase -= g_ * kGncStepStride; }, m);
    for (auto& o : solve_->handle(m)) {
      std::visit([&](auto& x) { x.phase += g_ * kGncStepStride; }, o.message);
      out.push_back(std::move(o));
    }
    if (solve_->done()) after_solve(out);
    return;
  }
  const std::uint32_t sender = sender_of(message);
  auto it = std::find(waiting_.begin(), waiting_.end(), sender);
  if (it == waiting_.end())
    throw std::runtime_error("agent " + std::to_string(in_.id) + ": unexpected robust message " +
                             std::to_string(phase) + " from agent " + std::to_string(sender));
  waiting_.erase(it);
  if (step_ == Step::kPoses) {
    const auto* block = std::get_if<PoseBlockMessage>(&message);
    if (!block)
      throw std::runtime_error("agent " + std::to_string(in_.id) + ": status where poses belong");
    state_->absorb(*block, neighbours_);
  } else {
    const auto* st = std::get_if<RoundStatusMessage>(&message);
    if (!st)
      throw std::runtime_error("agent " + std::to_string(in_.id) +
                               ": poses where a status belongs");
    if (step_ == Step::kVotes) votes_[sender] = {st->cost, st->grad_norm_sq};
    if (step_ == Step::kWeights) {
      votes_[sender] = {st->grad_norm_sq, 0};
      if (st->weights.size() != st->measurement_ids.size())
        throw std::runtime_error("agent " + std::to_string(in_.id) + ": weights from agent " +
                                 std::to_string(sender) + " do not match their measurements");
      for (std::size_t q = 0; q < st->weights.size(); ++q) {
        const auto pos = std::lower_bound(in_.measurement_index.begin(),
                                          in_.measurement_index.end(), st->measurement_ids[q]);
        const auto k = static_cast<std::size_t>(pos - in_.measurement_index.begin());
        if (pos == in_.measurement_index.end() || *pos != st->measurement_ids[q] ||
            weight_owner(in_.measurements[k], in_.owner) != static_cast<int>(sender))
          throw std::runtime_error("agent " + std::to_string(in_.id) + ": agent " +
                                   std::to_string(sender) + " sent the weight of measurement " +
                                   std::to_string(st->measurement_ids[q]) + ", not its own");
        weights_[k] = st->weights[q];
      }
    }
    if (step_ == Step::kRejected)
      rejected_.insert(rejected_.end(), st->measurement_ids.begin(), st->measurement_ids.end());
  }
  if (waiting_.empty()) after_exchange(out);
}

void GncAgent::replay(std::vector<OutgoingMessage>& out) {
  // Messages of the step just begun that came while this agent was behind.
  while (!done_ && !later_.empty()) {
    const std::uint32_t phase = later_.begin()->first;
    const bool current =
        step_ == Step::kSolve ? in_current_solve(phase) : phase == exchange_phase();
    if (!current) {
      const std::uint32_t lower = step_ == Step::kSolve ? g_ * kGncStepStride : exchange_phase();
      if (phase >= lower) return;
      later_.erase(later_.begin());  // of a step this agent has left
      continue;
    }
    std::vector<ProtocolMessage> kept = std::move(later_.begin()->second);
    later_.erase(later_.begin());
    const Step step = step_;
    const std::uint32_t g = g_;
    for (std::size_t q = 0; q < kept.size(); ++q) {
      if (done_ || step_ != step || g_ != g) {
        // The step moved on: what is left goes back in line.
        auto& back = later_[phase];
        back.insert(back.begin(), kept.begin() + static_cast<std::ptrdiff_t>(q), kept.end());
        break;
      }
      feed(kept[q], out);
    }
  }
}

std::vector<OutgoingMessage> GncAgent::handle(const ProtocolMessage& message) {
  std::vector<OutgoingMessage> out;
  if (done_) return out;
  const std::uint32_t phase = phase_of(message);
  const bool current = step_ == Step::kSolve ? in_current_solve(phase) : phase == exchange_phase();
  if (current) {
    feed(message, out);
    replay(out);
    return out;
  }
  const std::uint32_t lower = step_ == Step::kSolve ? g_ * kGncStepStride : exchange_phase();
  if (phase < lower) return out;  // a step this agent has left needs nothing more
  later_[phase].push_back(message);
  return out;
}

std::size_t GncAgent::messages_needed() const {
  if (done_) return 0;
  if (step_ == Step::kSolve) return std::max<std::size_t>(solve_->messages_needed(), 1);
  return std::max<std::size_t>(waiting_.size(), 1);
}

std::optional<AwaitedMessages> GncAgent::awaited() const {
  if (done_) return std::nullopt;
  if (step_ == Step::kSolve) {
    std::optional<AwaitedMessages> a = solve_->awaited();
    if (a) a->phase += g_ * kGncStepStride;
    return a;
  }
  return AwaitedMessages{0, exchange_phase(), waiting_};
}

}  // namespace tessera
