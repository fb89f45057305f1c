#include "coordinator/result_gathering.hpp"

#include <algorithm>
#include <optional>
#include <set>
#include <string>

#include "runtime/elapsed.hpp"
#include "transport/report_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

void await_final_estimates(CoordinatorSession& s, const CoordinatorOptions& options,
                           RoundReports& reports, LossHandling& losses, RunMonitor* monitor,
                           std::chrono::steady_clock::time_point t_run) {
  Mailroom& room = s.mailroom();
  // Called with the inbox locked (inside a wait's predicate).
  auto finals_missing = [&]() {
    std::set<std::uint32_t> have;
    for (const auto& f : s.finals().queued_locked())
      if (f.epoch() >= losses.record().epoch) have.insert(f.sender());
    std::string out;
    for (std::uint32_t k : losses.record().expected)
      if (!have.count(k)) out += (out.empty() ? "agent " : ", agent ") + std::to_string(k);
    return out;
  };
  const bool watch = monitor || losses.arbitrates();
  // Progress digests (a few a second from each agent) unless lost agents are arbitrated: the
  // arbiter then needs each agent's own latest round, and reads every round status.
  const bool digests = !losses.arbitrates();
  for (;;) {
    const double left = options.run_timeout_s - ms_since(t_run) / 1000.0;
    std::string absent;
    // Lost peers are noticed by polling the session (a few times a second) when watching.
    const double nap = watch ? std::min(std::max(0.0, left), 0.25) : std::max(0.0, left);
    WaitStatus st = room.wait_for(
        [&] {
          absent = finals_missing();
          return (absent.empty() && reports.results().have_final_report &&
                  (!digests || reports.results().have_final_digest)) ||
                 !s.status_watch().queued_locked().empty() ||
                 !s.reports().queued_locked().empty() || !s.progress().queued_locked().empty() ||
                 !s.rejoins().queued_locked().empty();
        },
        Seconds(nap));
    if (absent.empty() && digests && !reports.results().have_final_digest)
      absent = "agent 0 (its last progress digest)";
    if (st == WaitStatus::kStopped || (st == WaitStatus::kTimeout && left <= 0))
      expect_ready(st, room, options.run_timeout_s, "the final estimates",
                   "none yet from " + absent);
    const auto now = std::chrono::steady_clock::now();
    for (const auto& d : s.progress().take_all()) {
      if (!digests) continue;
      reports.on_digest(d, ms_since(t_run));
      if (!monitor) continue;
      std::optional<std::uint32_t> round;
      if (d.phase() != 0) round = d.round();
      monitor->on_digest(d.sender(), round, d.waiting_for(), d.waiting_s(), now, d.final());
    }
    for (const auto& m : s.status_watch().take_all()) {
      if (m.epoch() < losses.status_epoch()) continue;  // from before a rollback
      if (!is_round_status(m)) continue;
      losses.on_round_status(m.sender(), m.round(), now);
      reports.on_round_status(m, static_cast<std::uint32_t>(losses.record().expected.size()),
                              ms_since(t_run));
    }
    for (const auto& m : s.reports().take_all())
      if (m.epoch() >= losses.status_epoch()) reports.on_report(from_wire(m));
    if (watch) {
      switch (losses.watch(now)) {
        case LossHandling::Outcome::kRolledBack:
          reports.drop_partial_rounds();
          break;
        case LossHandling::Outcome::kRepartitioned:
          reports.restart_after_repartition();
          break;
        case LossHandling::Outcome::kNone:
          break;
      }
      if (monitor) monitor->tick(now);
    }
    if (reports.results().have_final_report && (!digests || reports.results().have_final_digest) &&
        s.finals().size() >= losses.record().expected.size() &&
        room.wait_for([&] { return finals_missing().empty(); }, Seconds(0)) == WaitStatus::kReady) {
      reports.finish();  // the last round's line, if the rate limit held it back
      return;
    }
  }
}

}  // namespace tessera::coordinator
