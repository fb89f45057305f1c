#include "runtime/run_monitor.hpp"

#include <algorithm>
#include <cstdio>
#include <tessera/util/input_error.hpp>

namespace tessera::coordinator {

namespace {
double secs(RunMonitor::Clock::duration d) {
  return std::chrono::duration<double>(d).count();
}
std::string list(const std::vector<std::uint32_t>& v) {
  std::string s;
  for (auto k : v) s += (s.empty() ? "" : ",") + std::to_string(k);
  return s;
}
}  // namespace

void MonitorOptions::validate() const {
  if (!(interval_s >= 0 && interval_s <= 86400))
    throw InputError("MonitorOptions.interval_s must be 0..86400 seconds, got " +
                     std::to_string(interval_s));
  if (lag_rounds < 1) throw InputError("MonitorOptions.lag_rounds must be >= 1, got 0");
  if (!(lag_s > 0 && lag_s <= 86400))
    throw InputError("MonitorOptions.lag_s must be in (0, 86400] seconds, got " +
                     std::to_string(lag_s));
}

RunMonitor::RunMonitor(std::uint32_t num_agents, MonitorOptions options, std::ostream& out,
                       Clock::time_point start)
    : n_(num_agents),
      opt_(options),
      out_(out),
      start_(start),
      last_print_(start),
      round_(num_agents, -1),
      last_seen_(num_agents, start),
      lost_(num_agents, false),
      wait_(num_agents),
      done_(num_agents, false) {
  opt_.validate();
}

void RunMonitor::on_status(std::uint32_t agent, std::uint32_t round, Clock::time_point now) {
  if (agent >= n_) return;
  // After a rollback rounds go back: the newest report is the agent's round.
  round_[agent] = round;
  last_seen_[agent] = now;
}

void RunMonitor::on_digest(std::uint32_t agent, std::optional<std::uint32_t> round,
                           const std::vector<std::uint32_t>& waiting_for, double waiting_s,
                           Clock::time_point now, bool final) {
  if (agent >= n_) return;
  digests_ = true;
  if (round) round_[agent] = *round;
  last_seen_[agent] = now;
  wait_[agent] = final ? Wait{} : Wait{waiting_for, waiting_s};
  done_[agent] = final;
}

void RunMonitor::set_lost(const std::vector<std::uint32_t>& lost, Clock::time_point now) {
  std::vector<bool> now_lost(n_, false);
  for (auto k : lost)
    if (k < n_) now_lost[k] = true;
  for (std::uint32_t k = 0; k < n_; ++k) {
    if (now_lost[k] == lost_[k]) continue;
    lost_[k] = now_lost[k];
    if (!now_lost[k]) last_seen_[k] = now;  // back: lag counts from now
    event(now_lost[k] ? "agent " + std::to_string(k) + " lost"
                      : "agent " + std::to_string(k) + " is back",
          now);
  }
}

void RunMonitor::event(const std::string& what, Clock::time_point now) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "status %.1fs: ", secs(now - start_));
  out_ << buf << what << "\n";
  print(now);
}

bool RunMonitor::silent(std::uint32_t k, Clock::time_point newest, Clock::time_point now) const {
  return secs(newest - last_seen_[k]) >= opt_.lag_s ||
         (secs(now - last_seen_[k]) >= opt_.lag_s && newest > last_seen_[k]);
}

RunMonitor::Clock::time_point RunMonitor::newest_report() const {
  Clock::time_point newest = start_;
  for (std::uint32_t k = 0; k < n_; ++k)
    if (!lost_[k]) newest = std::max(newest, last_seen_[k]);
  return newest;
}

std::vector<std::uint32_t> RunMonitor::lagging(Clock::time_point now) const {
  std::int64_t lead = -1;
  for (std::uint32_t k = 0; k < n_; ++k)
    if (!lost_[k]) lead = std::max(lead, round_[k]);
  const Clock::time_point newest = newest_report();
  std::vector<std::uint32_t> out;
  if (lead < 0) return out;  // nothing reported yet: set-up, not lag
  const std::vector<std::uint32_t> waited = waited_for(now).first;
  for (std::uint32_t k = 0; k < n_; ++k) {
    if (lost_[k] || done_[k]) continue;
    const bool behind = !digests_ && lead - round_[k] >= static_cast<std::int64_t>(opt_.lag_rounds);
    const bool waited_long = std::find(waited.begin(), waited.end(), k) != waited.end();
    if (behind || waited_long || silent(k, newest, now)) out.push_back(k);
  }
  return out;
}

std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>> RunMonitor::waited_for(
    Clock::time_point now) const {
  std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>> out;
  if (!digests_) return out;
  const Clock::time_point newest = newest_report();
  std::vector<bool> all(n_, true);
  for (std::uint32_t k = 0; k < n_; ++k) {
    // A silent agent's last wait is stale (it is named as silent instead).
    if (lost_[k] || wait_[k].senders.empty() || wait_[k].waiting_s < opt_.lag_s ||
        silent(k, newest, now))
      continue;
    out.second.push_back(k);
    std::vector<bool> named(n_, false);
    for (auto j : wait_[k].senders)
      if (j < n_) named[j] = true;
    for (std::uint32_t j = 0; j < n_; ++j) all[j] = all[j] && named[j];
  }
  if (out.second.empty()) return out;
  for (std::uint32_t j = 0; j < n_; ++j)
    if (all[j] && !lost_[j] && !done_[j]) out.first.push_back(j);
  // A hung agent's protocol messages stop with its digests, so an agent that needs them cannot
  // send its status either and is waited for as well, though its digests go on. When some of
  // the waited-for agents have gone quiet, they are the cause: name only them. Half of lag_s
  // is far above a live agent's digest period and below a hung agent's quiet time once a wait
  // has lasted lag_s.
  std::vector<std::uint32_t> quiet;
  for (auto j : out.first)
    if (secs(now - last_seen_[j]) >= opt_.lag_s / 2) quiet.push_back(j);
  if (!quiet.empty()) out.first = std::move(quiet);
  return out;
}

std::string RunMonitor::line(Clock::time_point now) const {
  std::vector<std::uint32_t> lost;
  std::uint32_t alive = 0;
  for (std::uint32_t k = 0; k < n_; ++k) lost_[k] ? lost.push_back(k) : void(++alive);
  char head[64];
  std::snprintf(head, sizeof(head), "status %.1fs: %u/%u agents alive; rounds", secs(now - start_),
                alive, n_);
  std::string s = head;
  for (std::uint32_t k = 0; k < n_; ++k)
    s += " " + std::to_string(k) + ":" + (round_[k] < 0 ? "-" : std::to_string(round_[k]));
  const auto lag = lagging(now);
  if (!lag.empty()) s += "; lagging: " + list(lag);
  const auto [waited, waiters] = waited_for(now);
  if (!waited.empty()) s += "; agents " + list(waiters) + " wait for " + list(waited);
  if (!lost.empty()) s += "; lost: " + list(lost);
  return s;
}

void RunMonitor::print(Clock::time_point now) {
  out_ << line(now) << "\n" << std::flush;
  last_print_ = now;
  last_lagging_ = lagging(now);
}

void RunMonitor::tick(Clock::time_point now) {
  if (lagging(now) != last_lagging_ ||
      (opt_.interval_s > 0 && secs(now - last_print_) >= opt_.interval_s))
    print(now);
}

double RunMonitor::seconds_to_next(Clock::time_point now) const {
  if (opt_.interval_s <= 0) return 1.0;  // still re-check lag once a second
  return std::max(0.0, std::min(1.0, opt_.interval_s - secs(now - last_print_)));
}

}  // namespace tessera::coordinator
