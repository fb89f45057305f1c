#pragma once
// The gate an agent passes before it announces itself: it must know the coordinator (whose
// participant tags say whether the run talks UDP only) and, in a secured run, have
// authenticated every other process of the run. Two things can make the agent re-create its
// participant (Session::replace_participant) on the way, each bounded:
// - the coordinator talks UDP only (its run keeps replicas / waits for rejoins) while this
//   agent's participant still has shared memory: one re-creation, UDP only;
// - DDS Security: a peer stays discovered but unauthenticated for `stall_after` (a Fast DDS 2.9
//   defect; which side of the pair re-creates: transport/fastdds/handshake_stall.hpp). At most
//   `max_reopens` times.
// Nothing was announced yet, so a re-created participant is invisible to the run except that
// peers forget the old one (ParticipantTags::replaces) instead of treating it as lost.

#include <functional>
#include <string>
#include <vector>

#include "transport/inbox.hpp"
#include "transport/peer_view.hpp"
#include "transport/run_identity.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

class Session;

struct PeerGateOptions {
  double timeout_s = 10;     ///< Bound on the whole gate (the agent's --timeout), > 0.
  double stall_after_s = 4;  ///< A handshake unfinished this long is stalled, > 0. Normal
                             ///< handshakes take < 1 s (a few under heavy load).
  int max_reopens = 3;       ///< Re-creations for stalled handshakes, >= 0.
  /// Test hook: re-create once as soon as a peer whose handshake this agent would cure is
  /// discovered but not authenticated (as if that handshake had stalled at once). Not counted
  /// in max_reopens, so a real stall after it is still cured (a stall bound of 1 ms used to
  /// force this left a real stall that followed nothing to cure it with).
  bool force_one_reopen = false;
  double retire_notice_s = 0.5;  ///< How long a participant announces that it retires before
                                 ///< it is deleted (Session::replace_participant), >= 0.
  /// The agent joins a run in progress (a restarted agent before its rejoin request): its
  /// peers never re-create, so it cures every stalled handshake itself
  /// (transport/fastdds/handshake_stall.hpp). Default false: a fresh set-up.
  bool joining = false;
  /// Throws InputError naming the bad field.
  void validate() const;
};

/// One look at the peers: what the gate does next.
struct GateStep {
  enum Kind {
    kWait,           ///< Not yet: `why` says what is missing.
    kPass,           ///< Announce now.
    kReopenUdpOnly,  ///< Re-create without shared memory (the coordinator talks UDP only).
    kReopenStalled,  ///< Re-create: the handshake with `why`'s peer stalled.
  } kind = kWait;
  std::string why;
};

/// Pure decision for agent `self` (SessionOptions of its current participant) given its live
/// peers. `secured`: the session uses DDS Security; `joining`: PeerGateOptions::joining.
GateStep judge_peers(const SessionOptions& self, bool secured, const std::vector<PeerView>& peers,
                     double stall_after_s, bool joining = false);

struct PeerGateResult {
  WaitStatus status = WaitStatus::kTimeout;  ///< kReady: passed; kStopped: the run stops.
  int udp_reopens = 0;                       ///< 0 or 1.
  int stall_reopens = 0;
  int forced_reopens = 0;           ///< 0 or 1 (PeerGateOptions::force_one_reopen).
  std::string missing;              ///< On kTimeout: what was still missing.
  std::vector<std::string> events;  ///< One line per re-creation (for the agent's log).
};

/// Runs the gate on `session` (an agent's, before its announcement or its rejoin request).
/// Judges again as soon as anything about the peers changes (discovery, loss, authentication,
/// endpoint match: Mailroom::notify_state_changed) and at least every 0.2 s, or every
/// stall_after_s / 2 when that is shorter (at least 1 ms; the stall bound is a duration, not an
/// event); a stop of the run ends it at once. With force_one_reopen (secured runs only) the
/// first look at an unauthenticated peer it would cure re-creates once, then stalls are judged
/// with stall_after_s and max_reopens as usual. `on_poll` (optional) runs before every look; what
/// it throws ends the gate.
PeerGateResult pass_peer_gate(Session& session, const PeerGateOptions& options,
                              const std::function<void()>& on_poll = {});

}  // namespace tessera::transport
