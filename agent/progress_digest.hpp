#pragma once
// An agent's progress digest for the coordinator (wire::AgentProgress, docs/dds-runtime.md,
// "Progress digests"). Why: for the coordinator to read every agent's status of every round
// (N deliveries and N wake-ups of its receive thread a round, ~1/5 of a cheap round's
// deliveries) only to print progress, time the rounds and spot lagging agents is waste. Each agent
// already sees every status of a step (it needs them for the step's sums), so it can tell the
// coordinator the same things a few times a second instead: the newest step it has seen
// complete with its sums, the step it still waits in and for whom, and the round timing.
//
// Pure bookkeeping (no DDS, no clock of its own): the channel feeds it the statuses it sends
// and receives and asks it when a digest is due. Only core's round statuses of the solve
// count (phases 1 and 5, transport/topic_names.hpp: is_solve_status_phase). Steps are keyed by
// (round, phase) alone: digests are only used in runs without rollbacks or re-partitions (the
// coordinator reads the statuses themselves while it arbitrates lost agents).

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

#include "tessera.h"

namespace tessera::agent {

struct ProgressDigestOptions {
  /// Seconds between digests while the rounds go on, (0, 60]. Bounds how often the
  /// coordinator prints a progress line (launch's output: at most ~10 lines a second) and how
  /// late its lag checks see an agent; 5 agents x 10 digests a second is ~1 % of a cheap
  /// round's deliveries (kitti_02: ~700 rounds a second, 27 deliveries each).
  double period_s = 0.1;

  /// Throws InputError naming the field when it is out of range.
  void validate() const;
};

class ProgressDigest {
 public:
  using Clock = std::chrono::steady_clock;

  /// `agent`: this agent's id; `num_agents`: statuses in a step; `reporter`: also send a
  /// digest at once when the first step and each restart step complete (the agent whose
  /// digests give the coordinator's progress lines and round timing: agent 0). Throws
  /// InputError when `options` are invalid.
  ProgressDigest(std::uint32_t agent, std::uint32_t num_agents, bool reporter,
                 ProgressDigestOptions options, Clock::time_point start);

  /// A round status this agent sent (`own`) or received. Ignores every phase but the solve's.
  void on_status(const RoundStatusMessage& m, bool own, Clock::time_point now);
  /// Whether a digest is due: the period passed since the last one, or (reporter) a first or
  /// restart step completed since.
  bool due(Clock::time_point now) const;
  /// When the next periodic digest is due (for bounded waits).
  Clock::time_point next_due() const { return last_sent_ + period_; }
  /// The digest as of `now` (run id left to the session); restarts the period. `final`: the
  /// solve is over, this is the agent's last.
  wire::AgentProgress take(Clock::time_point now, bool final = false);

 private:
  struct Step {
    std::vector<std::optional<std::pair<double, double>>> by_sender;  // cost, grad_norm_sq
    std::uint32_t count = 0;
    std::optional<Clock::time_point> own_at;  // when this agent sent its status
  };
  using Key = std::pair<std::uint32_t, std::uint32_t>;  // round, phase
  void complete(const Key& key, const Step& step, Clock::time_point now);

  std::uint32_t agent_, n_;
  bool reporter_;
  Clock::duration period_;
  Clock::time_point last_sent_;
  std::map<Key, Step> open_;
  // The newest completed step and its sums (agent-id order, as core sums them).
  std::optional<Key> done_;
  double cost_ = 0, grad_norm_sq_ = 0;
  std::uint32_t completed_rounds_ = 0;
  std::optional<Clock::time_point> first_done_;
  Clock::time_point last_done_;
  bool event_ = false;
};

}  // namespace tessera::agent
