#pragma once
// What an operator sees while a distributed run goes on (issue 8 item 5): which agents are
// alive, the round each one has reported, and which are lagging or lost. Fed with the agents'
// round statuses (which the coordinator reads anyway) and the session's peer events; prints a
// status line every `interval_s` seconds and at once when something changes (an agent lost,
// rejoined, starts or stops lagging).
//
// Lagging: an agent whose last reported round is at least `lag_rounds` behind the most
// advanced agent, or that has reported nothing for `lag_s` seconds while another agent has.

#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
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
  void print(Clock::time_point now);
  std::uint32_t n_;
  MonitorOptions opt_;
  std::ostream& out_;
  Clock::time_point start_, last_print_;
  std::vector<std::int64_t> round_;  // -1: nothing reported yet
  std::vector<Clock::time_point> last_seen_;
  std::vector<bool> lost_;
  std::vector<std::uint32_t> last_lagging_;
};

}  // namespace tessera::coordinator
