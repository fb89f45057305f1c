#include "agent/progress_digest.hpp"

#include <string>
#include <tessera/util/input_error.hpp>

#include "transport/topic_names.hpp"

namespace tessera::agent {

void ProgressDigestOptions::validate() const {
  if (!(period_s > 0 && period_s <= 60))
    throw InputError("ProgressDigestOptions.period_s must be in (0, 60] seconds, got " +
                     std::to_string(period_s));
}

ProgressDigest::ProgressDigest(std::uint32_t agent, std::uint32_t num_agents, bool reporter,
                               ProgressDigestOptions options, Clock::time_point start)
    : agent_(agent), n_(num_agents), reporter_(reporter), last_sent_(start) {
  options.validate();
  period_ =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.period_s));
}

void ProgressDigest::on_status(const RoundStatusMessage& m, bool own, Clock::time_point now) {
  if (!transport::is_solve_status_phase(m.phase) || m.sender >= n_) return;
  const Key key{m.round, m.phase};
  // An agent completes its steps in protocol order, so a step older than the newest
  // completed one is a duplicate (never the case over DDS) and would only linger here.
  if (done_ && key <= *done_) return;
  Step& step = open_[key];
  if (step.by_sender.empty()) step.by_sender.resize(n_);
  if (!step.by_sender[m.sender]) ++step.count;
  step.by_sender[m.sender] = std::make_pair(m.cost, m.grad_norm_sq);
  if (own) step.own_at = now;
  if (step.count < n_) return;
  complete(key, step, now);
  open_.erase(open_.begin(), open_.upper_bound(key));
}

void ProgressDigest::complete(const Key& key, const Step& step, Clock::time_point now) {
  cost_ = grad_norm_sq_ = 0;
  for (const auto& v : step.by_sender) {  // agent-id order, as core sums the step
    cost_ += v->first;
    grad_norm_sq_ += v->second;
  }
  if (!first_done_) {
    first_done_ = now;
    event_ = reporter_;
  }
  if (key.second == 5) event_ = reporter_;  // a momentum restart: always its own line
  if (key.second == 1) ++completed_rounds_;
  last_done_ = now;
  done_ = key;
}

bool ProgressDigest::due(Clock::time_point now) const {
  return event_ || now >= next_due();
}

wire::AgentProgress ProgressDigest::take(Clock::time_point now, bool final) {
  wire::AgentProgress d;
  d.sender(agent_);
  if (done_) {
    d.round(done_->first);
    d.phase(done_->second);
    d.cost(cost_);
    d.grad_norm_sq(grad_norm_sq_);
  }
  // The step this agent sent its status for and still waits in: at most one (its next
  // status leaves only once this step is complete).
  for (const auto& [key, step] : open_) {
    if (!step.own_at) continue;
    std::vector<std::uint32_t> missing;
    for (std::uint32_t k = 0; k < n_; ++k)
      if (!step.by_sender[k]) missing.push_back(k);
    d.waiting_for(missing);
    d.waiting_round(key.first);
    d.waiting_s(std::chrono::duration<double>(now - *step.own_at).count());
    break;
  }
  d.completed_rounds(completed_rounds_);
  if (first_done_)
    d.first_to_last_ms(
        std::chrono::duration<double, std::milli>(last_done_ - *first_done_).count());
  d.final(final);
  last_sent_ = now;
  event_ = false;
  return d;
}

}  // namespace tessera::agent
