#pragma once
// This agent's part in surviving a permanent loss (coordinator --replicas K; see
// docs/fault-tolerance.md): it sends its local problem once and its lifted poses every few
// rounds to the K agents that keep its replica, keeps the replicas other agents send it, and
// when the coordinator re-partitions for the survivors, takes over its new block from its
// own data, the other survivors' and the replicas of the lost agent.

#include <cstdint>
#include <optional>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <vector>

#include "agent/dds_channel.hpp"
#include "runtime/agent_log.hpp"
#include "runtime/round_loop.hpp"
#include "runtime/survivor_takeover.hpp"
#include "tessera.h"
#include "transport/agent_session.hpp"

namespace tessera::agent {

class BlockReplication {
 public:
  /// Agent `self` with `replicas` holders (0: disabled; then only enabled() is called),
  /// sending its lifted poses every `replica_every` (>= 1) rounds.
  BlockReplication(transport::AgentSession& session, std::uint32_t self, std::uint32_t replicas,
                   std::uint32_t replica_every, const AgentLog& log)
      : session_(session),
        self_(self),
        replicas_(replicas),
        replica_every_(replica_every),
        log_(log) {}

  bool enabled() const { return replicas_ > 0; }
  /// Sends `local`'s problem and lifted start to its holders and waits (at most `timeout_s`)
  /// until they acknowledged it, so that from this agent's first round on a loss of it is
  /// covered; makes `channel` keep the lifted-pose replicas of other agents instead of
  /// handing them to the round protocol.
  void start(const AgentLocalData& local, DdsProtocolChannel& channel, double timeout_s);
  /// After each round of `local` (the block in force): remembers the lifted poses (the
  /// take-over starts from them); every replica_every rounds, before any take-over, sends
  /// them to the holders.
  void on_round(const AgentLocalData& local, const ProtocolSnapshot& snap);
  /// The survivors' re-partition `asg` arrived: exchanges with the other survivors and
  /// returns this agent's new block (kept here; valid while this object lives). Moves the
  /// session to the new epoch. Throws RunFailure on a stop or timeout.
  const AgentLocalData& take_over(const AgentLocalData& local, const wire::PartitionAssignment& asg,
                                  double timeout_s);

 private:
  transport::AgentSession& session_;
  std::uint32_t self_;
  std::uint32_t replicas_, replica_every_;
  AgentLog log_;
  std::vector<std::uint32_t> holders_;  // who keeps this agent's replica
  ReplicaStore store_;                  // replicas this agent keeps
  Eigen::MatrixXd Y_;                   // latest lifted poses (consistent point)
  std::uint32_t round_ = 0;
  std::optional<AgentLocalData> taken_;  // the new block after a re-partition
};

}  // namespace tessera::agent
