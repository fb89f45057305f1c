#pragma once
// What an operator sees while a distributed run goes on (issue 8 item 5): which agents are
// alive, the round each one has reported, and which are lagging or lost. Fed with the agents'
// progress digests (agent/progress_digest.hpp; a few a second) or, while the coordinator
// arbitrates lost agents, their round statuses, and with the session's peer events; prints a
// status line every `interval_s` seconds and at once when something changes (an agent lost,
// rejoined, starts or stops lagging).
//
// Lagging: an agent that has reported nothing for `lag_s` seconds while another agent has
// (a hung process: its digests stop too); with round statuses, one whose last reported round
// is at least `lag_rounds` behind the most advanced agent; with digests, one that every agent
// waiting for at least `lag_s` in its current step waits for (digests are samples taken at
// different moments, so their rounds are not compared; a waiting agent names the senders it
// misses, and with the status relay the agents other than the relay miss everyone, hence the
// intersection). An agent blocked on a hung agent's messages is waited for too but still
// sends digests: when some waited-for agents have gone quiet (no digest for lag_s / 2), only
// they are named. The line then adds "agents A,B wait for K".

#include <chrono>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace tessera::coordinator {

struct MonitorOptions {
  /// Seconds between periodic status lines, 0..86400; 0 = only on changes.
  double interval_s = 5.0;
  /// Rounds behind the most advanced agent that make an agent lagging, >= 1.
  std::uint32_t lag_rounds = 2;
  /// Seconds of silence (while another agent reported) that make an agent lagging, > 0.
  double lag_s = 3.0;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

class RunMonitor {
 public:
  using Clock = std::chrono::steady_clock;
  /// Throws InputError when `options` are invalid (MonitorOptions::validate).
  RunMonitor(std::uint32_t num_agents, MonitorOptions options, std::ostream& out,
             Clock::time_point start);

  void on_status(std::uint32_t agent, std::uint32_t round, Clock::time_point now);
  /// A progress digest from `agent`: `round` (nullopt: no step completed yet), and whom it
  /// waits for in its current step (agent ids) since `waiting_s` seconds. After its `final`
  /// digest an agent sends none (it is done with the rounds): never lagging from then on.
  void on_digest(std::uint32_t agent, std::optional<std::uint32_t> round,
                 const std::vector<std::uint32_t>& waiting_for, double waiting_s,
                 Clock::time_point now, bool final = false);
  /// The set of agents currently lost (from the session); reports changes.
  void set_lost(const std::vector<std::uint32_t>& lost, Clock::time_point now);
  /// A one-off event line ("agent 2 rejoined: rollback to round 14").
  void event(const std::string& what, Clock::time_point now);
  /// Prints the periodic line when due, or at once when the lagging set changed.
  void tick(Clock::time_point now);
  /// The current status line (without the trailing newline).
  std::string line(Clock::time_point now) const;
  /// Seconds until the next periodic line (for bounded waits).
  double seconds_to_next(Clock::time_point now) const;

 private:
  std::vector<std::uint32_t> lagging(Clock::time_point now) const;
  /// When the most recent report of an agent not lost came (start if none).
  Clock::time_point newest_report() const;
  bool silent(std::uint32_t k, Clock::time_point newest, Clock::time_point now) const;
  /// With digests: the agents every long waiter waits for, and those waiters.
  std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>> waited_for(
      Clock::time_point now) const;
  struct Wait {
    std::vector<std::uint32_t> senders;
    double waiting_s = 0;
  };
  void print(Clock::time_point now);
  std::uint32_t n_;
  MonitorOptions opt_;
  std::ostream& out_;
  Clock::time_point start_, last_print_;
  std::vector<std::int64_t> round_;  // -1: nothing reported yet
  std::vector<Clock::time_point> last_seen_;
  std::vector<bool> lost_;
  std::vector<std::uint32_t> last_lagging_;
  bool digests_ = false;    // fed by on_digest: rounds are samples, compare waits instead
  std::vector<Wait> wait_;  // the newest digest's wait, per agent
  std::vector<bool> done_;  // sent its final digest
};

}  // namespace tessera::coordinator
