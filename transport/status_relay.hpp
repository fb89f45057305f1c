#pragma once
// Round statuses through one relay agent instead of all to all (docs/dds-runtime.md,
// "Round statuses through a relay"). Each round's status step is a reduction every agent computes
// over the N statuses; sent all to all over DDS it costs N (N - 1) deliveries, plus N to the
// coordinator, and every delivery wakes a Fast DDS receive thread (the cost that dominates a cheap
// round on 2 cores). Relayed, the other agents send their status to the relay agent only (its own
// topic, kRelayStatusTopic), and the relay, once it has all N of a step, sends them as one
// bundle on kStatusTopic, which every agent and the coordinator read: 2 (N - 1) + 1
// deliveries instead of N^2. The statuses themselves are unchanged (each receiver unpacks the
// bundle into the same N - 1 messages and core sums them in agent-id order as before), so the
// iterates are identical. Only core's round statuses of the solve are relayed (relayed_phase);
// internal to transport/.

#include <cstdint>
#include <map>
#include <tessera/protocol/messages.hpp>
#include <tuple>
#include <vector>

#include "tessera.h"
#include "transport/topic_names.hpp"

namespace tessera::transport {

/// Protocol id of the relay agent.
inline constexpr std::uint32_t kRelayAgent = 0;
/// Runs of fewer agents broadcast their statuses (with 2 agents relaying saves nothing).
inline constexpr std::uint32_t kMinAgentsForRelay = 3;

/// Whether statuses of this phase are relayed: core's round statuses of the solve
/// (is_solve_status_phase), the ones the coordinator reads for progress and loss handling.
inline bool relayed_phase(std::uint32_t phase) {
  return is_solve_status_phase(phase);
}

/// Whether a pose block of this phase to the relay may ride in the sender's relayed status
/// sample (Session::send_all): the solve's blocks (core's ProtocolPhase kInit, kUpdate,
/// kRedoUpdate, and kCoarseTerms: the relay is the coarse solver, coarse_exchange.hpp), which
/// core buffers by (round, phase, sender), so that they may arrive on another topic than the
/// sender's other blocks.
inline bool rides_with_status(std::uint32_t phase) {
  return phase == 0 || phase == 3 || phase == 4 || phase == 6;
}

/// The relay's collection of one process. Not thread-safe: the session guards it with its
/// mailroom lock (statuses arrive on a listener thread, the bundle leaves on the main thread).
class StatusRelay {
 public:
  explicit StatusRelay(std::uint32_t num_agents) : num_agents_(num_agents) {}

  /// Records a status of a relayed phase (own or received). Statuses of epochs below
  /// `current_epoch` are dropped with everything collected for them. Returns true when this
  /// completed a step: all N statuses of its (epoch, round, phase), the relay's own among
  /// them (so a step completes only once this process is in it).
  bool add(const wire::RoundStatus& m, std::uint32_t current_epoch);
  /// Removes and returns every completed step as one bundle sample each (sender = the relay,
  /// the step's epoch, round and phase; bundle() = pack() of the N statuses, by sender).
  std::vector<wire::RoundStatus> take_bundles(const std::string& run_id, std::uint32_t relay);

  /// The bundle field of N statuses: per status, its sender, cost, squared gradient norm,
  /// block gradient norm, restart vote and done vote (doubles hold all of them exactly).
  static std::vector<double> pack(const std::vector<wire::RoundStatus>& statuses);
  /// The statuses a bundle sample carries, each with the bundle's run id, epoch, round and
  /// phase, as broadcasts. Throws TransportError on a malformed bundle.
  static std::vector<wire::RoundStatus> unpack(const wire::RoundStatus& bundle);

 private:
  using Step = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;  // epoch, round, phase
  std::uint32_t num_agents_;
  std::map<Step, std::map<std::uint32_t, wire::RoundStatus>> steps_;  // by sender
  std::vector<Step> complete_;
};

}  // namespace tessera::transport
