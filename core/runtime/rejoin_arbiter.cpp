#include "runtime/rejoin_arbiter.hpp"

#include <algorithm>
#include <cstdio>

namespace tessera::coordinator {

RejoinArbiter::RejoinArbiter(std::uint32_t num_agents, double rejoin_timeout_s)
    : n_(num_agents), timeout_s_(rejoin_timeout_s), reached_(num_agents, -1) {}

void RejoinArbiter::on_status(std::uint32_t agent, std::uint32_t round) {
  if (agent < n_) reached_[agent] = std::max<std::int64_t>(reached_[agent], round);
}

void RejoinArbiter::on_lost(std::uint32_t agent, Clock::time_point now) {
  if (agent < n_) lost_since_.emplace(agent, now);
}

void RejoinArbiter::on_rejoin(const RejoinRequest& request, Clock::time_point now) {
  if (request.agent >= n_) return;
  lost_since_.emplace(request.agent, now);
  requests_[request.agent] = request;
}

std::optional<double> RejoinArbiter::seconds_to_deadline(Clock::time_point now) const {
  std::optional<double> out;
  for (const auto& [agent, since] : lost_since_) {
    const double left = timeout_s_ - std::chrono::duration<double>(now - since).count();
    out = out ? std::min(*out, left) : left;
  }
  return out;
}

void RejoinArbiter::forget(std::uint32_t agent) {
  if (!requests_.count(agent)) lost_since_.erase(agent);
}

LossDecision RejoinArbiter::decide(Clock::time_point now) {
  LossDecision d;
  if (lost_since_.empty()) return d;
  for (const auto& [agent, since] : lost_since_) {
    if (requests_.count(agent)) continue;
    if (std::chrono::duration<double>(now - since).count() >= timeout_s_) {
      d.kind = LossDecision::Kind::kGiveUp;
      d.agent = agent;
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%g", timeout_s_);
      d.reason = "agent " + std::to_string(agent) + " was lost and " +
                 (timeout_s_ > 0 ? std::string("did not rejoin within ") + buf + " s"
                                 : std::string("rejoining is off (--rejoin-timeout 0)"));
      // THE PLUG-IN POINT for re-partitioning for the survivors (issue 8 item 2).
      return d;
    }
    return d;  // still inside its window
  }
  // Every lost agent asked to rejoin: the rollback round is a checkpoint round of every
  // rejoining agent that every other agent has reached.
  std::vector<std::uint32_t> candidates;
  const RejoinRequest& first = requests_.at(lost_since_.begin()->first);
  for (std::uint32_t c : {first.round, first.round_prev}) {
    bool ok = true;
    for (const auto& [agent, req] : requests_)
      if (lost_since_.count(agent)) ok = ok && (req.round == c || req.round_prev == c);
    for (std::uint32_t a = 0; a < n_; ++a)
      if (!lost_since_.count(a)) ok = ok && reached_[a] >= static_cast<std::int64_t>(c);
    if (ok) candidates.push_back(c);
  }
  if (candidates.empty()) {
    d.kind = LossDecision::Kind::kGiveUp;
    d.agent = first.agent;
    std::string reached;
    for (std::uint32_t a = 0; a < n_; ++a)
      if (!lost_since_.count(a))
        reached +=
            (reached.empty() ? "" : ", ") + std::to_string(a) + ":" + std::to_string(reached_[a]);
    d.reason = "agent " + std::to_string(first.agent) + " rejoined with checkpoint rounds " +
               std::to_string(first.round_prev) + " and " + std::to_string(first.round) +
               ", which not every agent can go back to (rounds reached: " + reached + ")";
    return d;
  }
  d.kind = LossDecision::Kind::kRollback;
  d.agent = first.agent;
  d.nonce = first.nonce;
  d.round = *std::max_element(candidates.begin(), candidates.end());
  d.epoch = ++epoch_;
  for (const auto& [agent, since] : lost_since_) {
    reached_[agent] = d.round;
    d.rejoined.push_back(requests_.at(agent));
  }
  lost_since_.clear();
  requests_.clear();
  return d;
}

}  // namespace tessera::coordinator
