#pragma once
// Whether the processes of a run can reach each other: which peers each endpoint must match,
// which remote participants each endpoint has matched (from the listeners), READY and
// FINISHED from the other processes, and the waits built on them (the readiness barrier,
// the linger before leaving on an error). Internal to transport/; state is guarded by the
// mailroom's mutex.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "transport/dds_trace.hpp"
#include "transport/inbox.hpp"
#include "transport/peer_tracking.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

/// Which peers an endpoint must match before the readiness barrier can pass.
/// kAgent: one agent, named when the expectation is registered (Readiness::expect).
enum class Expect {
  kNone,
  kOtherAgents,
  kOtherAgentsAndCoordinator,
  kCoordinator,
  kAllAgents,
  kAgent
};

class Readiness {
 public:
  Readiness(Mailroom& room, const SessionOptions& options, PeerIdentity me,
            const PeerTracker& peers, const DdsTrace& trace);

  /// Endpoint `endpoint` ("<topic>/w" or "<topic>/r") must match the peers of `e` (kNone:
  /// no requirement; kAgent: agent `agent`). Called while the endpoints are created.
  void expect(const std::string& endpoint, Expect e, std::uint32_t agent = 0);
  /// Listener event: `endpoint` matched (change > 0) or unmatched (< 0) an endpoint of the
  /// participant `prefix` (own participant ignored). Wakes waiters.
  void on_matched(const std::string& endpoint, const GuidPrefix& prefix, int change);
  /// READY received from `from`. Wakes waiters.
  void on_ready(const PeerIdentity& from);
  /// FINISHED received from the coordinator. Wakes waiters.
  void on_finished();
  /// ABORT received from `from` (its own or relayed). Wakes waiters.
  void on_abort(const PeerIdentity& from);

  /// Forgets every endpoint match (the participant they belonged to was replaced:
  /// Session::replace_participant); READY/FINISHED received are kept.
  void forget_matches();

  /// The peers of a complete run that `e` names (without a coordinator when the run has none;
  /// kAgent: agent `one`).
  std::vector<PeerIdentity> expected_peers(Expect e, std::uint32_t one = 0) const;
  /// Whether every expected endpoint matched every live expected peer; else `missing` (if
  /// given) lists the absent peers. Locks the mailroom.
  bool endpoints_matched(std::string* missing) const;
  bool finished() const;
  /// FINISHED received, readable without the mutex (from a signal handler: the agent's
  /// end-of-run cover, transport/fastdds/teardown_guard.hpp). Lives as long as this object.
  const std::atomic<bool>& finished_flag() const { return finished_; }
  WaitStatus wait_finished(Seconds timeout);

  /// The readiness barrier: waits until endpoints_matched(), calls `send_ready`, then waits
  /// for READY from every other agent (and the coordinator, for agents), all within
  /// `timeout`. On kTimeout `missing` names who is not ready and `dump_match_state` is
  /// called (trace of what each endpoint matched). `ready_reader` ("<topic>/r"): the endpoint
  /// READY arrives on; a peer whose READY did not come is named with what this process knows
  /// of it (describe_not_ready_locked).
  WaitStatus barrier(Seconds timeout, std::string* missing, const std::function<void()>& send_ready,
                     const std::function<void()>& dump_match_state,
                     const std::string& ready_reader);
  /// Waits (not interrupted by a stop, bounded by `timeout`) until `endpoint` has matched
  /// every other process of the run or that process is gone; processes never discovered are
  /// waited for only `unseen_patience`. Returns when done, whatever the outcome.
  void wait_matched_or_gone(const std::string& endpoint, Seconds timeout, Seconds unseen_patience);
  /// Agents of a run with a coordinator, leaving on an error: waits (not interrupted by a
  /// stop, bounded by `timeout`) until the coordinator has acknowledged the abort, i.e. sent
  /// an ABORT of its own (it relays the cause that stopped it, which is ours when ours
  /// reached it first), or is gone. A coordinator not discovered yet is waited for too: it
  /// is the process that must name the cause. Returns at once for the coordinator itself
  /// and in runs without one; true when acknowledged or gone.
  bool wait_coordinator_acknowledged(Seconds timeout);

  // ---- with the mailroom's mutex held ------------------------------------------------------
  bool endpoints_matched_locked(std::string* missing) const;
  /// Whether `endpoint` has matched a live participant of `who`.
  bool has_matched_locked(const std::string& endpoint, const PeerIdentity& who) const;
  /// " <peer> <peer> ..." the listeners report as matched on `endpoint` (for traces).
  std::string describe_matched_locked(const std::string& endpoint) const;
  /// `who` followed by why its READY may be missing: "(not discovered)", "(lost)",
  /// "(discovered, its writer not matched by <ready_reader>)" or "(its writer matched, nothing
  /// received)".
  std::string describe_not_ready_locked(const PeerIdentity& who,
                                        const std::string& ready_reader) const;

 private:
  /// The other agents, and the coordinator for an agent of a run that has one.
  std::vector<PeerIdentity> other_processes() const;

  Mailroom& room_;
  const SessionOptions& opt_;
  PeerIdentity me_;
  const PeerTracker& peers_;
  const DdsTrace& trace_;
  std::map<std::string, std::multiset<GuidPrefix>>
      matched_;  // endpoint name -> matched remote participants
  std::map<std::string, std::pair<Expect, std::uint32_t>> expect_;  // with kAgent's agent
  std::set<std::string> ready_from_;   // describe() of peers that published READY
  std::atomic<bool> finished_{false};  // set under the mutex; atomic for finished_flag()
  bool coordinator_aborted_ = false;   // an ABORT came from the coordinator
};

}  // namespace tessera::transport
