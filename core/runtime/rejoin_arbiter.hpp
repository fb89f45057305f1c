#pragma once
// THE decision point for a lost agent (team convention: the coordinator is the arbiter).
//
// When an agent is lost (its process died), the coordinator waits up to the rejoin timeout
// for a process with the same id to come back (restarted from its checkpoint) and ask to
// rejoin. It then picks the rollback round: the newest of the restarted agent's checkpoint
// rounds that every other agent has reached (an agent that sent the status of round k holds
// its snapshot of round k), and every agent resumes from its snapshot of that round at a new
// epoch. If nobody comes back in time the arbiter gives up: today the run stops cleanly with
// a message naming the lost agent; a re-partition for the survivors plugs in at kGiveUp
// (see decide()).

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace tessera::coordinator {

using Clock = std::chrono::steady_clock;

struct RejoinRequest {
  std::uint32_t agent = 0;
  std::uint32_t round = 0;       ///< Newest checkpoint round.
  std::uint32_t round_prev = 0;  ///< The one before (= round when there is only one).
  std::uint64_t nonce = 0;       ///< Echoed in the rollback order.
};

struct LossDecision {
  enum class Kind {
    kWait,      ///< Nothing to do yet.
    kRollback,  ///< Tell every agent: resume from `round` at `epoch` (agent rejoined).
    kGiveUp     ///< Nobody came back in time (or cannot be taken back): `reason` says why.
  };
  Kind kind = Kind::kWait;
  std::uint32_t agent = 0;
  std::uint32_t round = 0;
  std::uint32_t epoch = 0;
  std::uint64_t nonce = 0;
  /// kRollback: every rejoining agent and its nonce (one order each; same round and epoch).
  std::vector<RejoinRequest> rejoined;
  std::string reason;
};

class RejoinArbiter {
 public:
  /// `rejoin_timeout_s` <= 0: no waiting, a lost agent gives up at once.
  RejoinArbiter(std::uint32_t num_agents, double rejoin_timeout_s);

  /// A round status of the current epoch from `agent` (it holds its snapshot of `round`).
  void on_status(std::uint32_t agent, std::uint32_t round);
  /// `agent`'s process is gone (idempotent while it is lost).
  void on_lost(std::uint32_t agent, Clock::time_point now);
  /// A restarted process asks to rejoin (counts as lost if the loss was not seen yet).
  void on_rejoin(const RejoinRequest& request, Clock::time_point now);

  /// Drops a lost agent that turned out to be alive (the lease of a busy host expired and the
  /// same process was discovered again) and never asked to rejoin; no rollback follows.
  void forget(std::uint32_t agent);

  /// The decision point: a rollback once every lost agent asked to rejoin and a common round
  /// exists; give up when a lost agent's window expired; otherwise wait. After kRollback the
  /// epoch has advanced and the agents are no longer lost.
  LossDecision decide(Clock::time_point now);

  std::uint32_t epoch() const { return epoch_; }
  bool anyone_lost() const { return !lost_since_.empty(); }
  /// Seconds until the earliest rejoin window closes (for bounded waits), or nullopt.
  std::optional<double> seconds_to_deadline(Clock::time_point now) const;

 private:
  std::uint32_t n_;
  double timeout_s_;
  std::uint32_t epoch_ = 0;
  std::vector<std::int64_t> reached_;  // highest status round per agent (-1: none)
  std::map<std::uint32_t, Clock::time_point> lost_since_;
  std::map<std::uint32_t, RejoinRequest> requests_;
};

}  // namespace tessera::coordinator
