#pragma once
// Permanent loss of an agent, the agents' side (no DDS here: pure bookkeeping, shared by the
// agent executable and tests). See docs/fault-tolerance.md.
//
// 1. Replication: after the hand-off every agent sends its local problem (every measurement
//    touching its poses, and its lifted initial poses) to its replica holders
//    (core/include/tessera/distributed/replica_plan.hpp), and every `replica_every` rounds its
//    current lifted poses. A holder keeps them in a ReplicaStore.
// 2. Take-over: when the coordinator publishes a re-partition for the survivors, every survivor
//    sends every other survivor one take-over message: the measurements touching the poses the
//    recipient gains (from its own problem and from the replicas of lost agents it holds) and
//    the lifted poses it can give for them (its own current ones, or a lost agent's replica).
//    Each survivor then assembles its new local problem, whose starting point is the current
//    iterate for its own poses and the (possibly a few rounds stale) replica for the lost ones.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <set>
#include <tessera/graph/measurement.hpp>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

/// PoseBlock phase of lifted-pose replicas: intercepted by the agent, never given to the
/// round protocol (core's phases are < kRoundingPhaseBase; the final report is 200).
constexpr std::uint32_t kReplicaPhase = 300;

/// What a holder keeps of one other agent.
struct Replica {
  std::vector<Measurement> measurements;  ///< Every measurement touching the agent's poses.
  std::vector<std::uint64_t> measurement_index;
  std::map<std::uint32_t, std::vector<double>> lifted;  ///< Pose id -> r*(d+1), column-major.
  std::uint32_t round = 0;                              ///< Round of `lifted`.
  bool has_problem = false;                             ///< The measurements arrived.
};

class ReplicaStore {
 public:
  /// Agent `a`'s local problem and its lifted poses of `round` (`width` = r*(d+1) doubles each).
  void absorb_problem(std::uint32_t a, std::vector<Measurement> measurements,
                      std::vector<std::uint64_t> measurement_index,
                      const std::vector<std::uint32_t>& ids, const std::vector<double>& lifted,
                      std::size_t width, std::uint32_t round);
  /// A lifted-pose replica (PoseBlock of phase kReplicaPhase from its owner). Replicas of an
  /// older round than the one held are ignored. Throws std::runtime_error on a malformed block.
  void absorb_poses(const PoseBlockMessage& m);
  const Replica* find(std::uint32_t a) const;

 private:
  std::map<std::uint32_t, Replica> by_agent_;
};

/// The lifted-pose replica this agent sends to its holders (phase kReplicaPhase): its owned
/// poses of `Y` (r x (d+1)m, `owned` order) at `round`.
PoseBlockMessage replica_block(std::uint32_t self, std::uint32_t round, int d,
                               const std::vector<std::uint32_t>& owned, const Eigen::MatrixXd& Y);

/// A re-partition for the survivors, as published by the coordinator.
struct Reassignment {
  std::uint32_t epoch = 0;
  std::vector<std::uint32_t> old_owner;  ///< Agent (id) of every pose before.
  std::vector<std::uint32_t> new_owner;  ///< Surviving agent (id) of every pose now.
  std::vector<std::uint32_t> survivors;  ///< Ascending; protocol id = position here.
  std::vector<std::uint32_t> lost;
};

/// What this agent holds when the re-partition arrives.
struct TakeoverSource {
  std::uint32_t self = 0;        ///< Agent id.
  const AgentLocalData* local;   ///< Its local problem (owned poses as of old_owner).
  Eigen::MatrixXd Y;             ///< Its latest lifted poses (local->owned order).
  std::uint32_t round = 0;       ///< Round of Y.
  const ReplicaStore* replicas;  ///< Replicas it holds.
};

/// One take-over message (decoded or to encode).
struct TakeoverMessage {
  std::uint32_t sender = 0;
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;
  std::vector<std::uint32_t> lifted_ids;
  std::vector<double> lifted_data;  ///< r*(d+1) per pose.
  std::uint32_t round = 0;
};

/// What `src` sends to survivor `recipient`: measurements touching the poses it gains (which it
/// did not own before) and lifted poses for them (own, or a lost agent's replica).
TakeoverMessage plan_takeover(const TakeoverSource& src, const Reassignment& r,
                              std::uint32_t recipient);

/// The survivor's new local problem (protocol ids 0..S-1, owner as protocol ids) with
/// `lifted_start` set. Checks completeness against `structure` (endpoints of every measurement):
/// every measurement touching an owned pose is present (none lost) and every owned pose has a
/// starting point; throws std::runtime_error naming what is missing otherwise.
AgentLocalData assemble_takeover(const TakeoverSource& src, const Reassignment& r,
                                 const std::vector<TakeoverMessage>& received);

}  // namespace tessera::agent
