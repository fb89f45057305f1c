#pragma once
// Runs N agents' round protocols in one process by handing each emitted message to its
// recipients. The DDS runtime delivers the same messages; because each agent buffers messages
// by (round, phase) and reduces in agent-id order, the delivery order cannot change iterates.
// The orders here exist to test exactly that.

#include <cstddef>
#include <cstdint>
#include <map>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <utility>
#include <vector>

namespace tessera {

enum class DeliveryOrder {
  kFifo,      ///< Oldest message first (agents started in id order).
  kReversed,  ///< Newest message first (agents started in reverse id order).
  kShuffled   ///< A pseudo-random pending message each time (delivery_seed).
};

struct DeliveryStats {
  std::uint64_t messages = 0;  ///< Deliveries (a broadcast to N-1 agents counts N-1).
  std::uint64_t bytes = 0;     ///< Payload bytes over all deliveries.
  std::vector<std::uint64_t> bytes_per_round;  ///< By the messages' round field.
  /// By the stage of the certified sequence (stage_tag.hpp; stage 0 = the first solve).
  std::vector<std::uint64_t> bytes_per_stage;
  /// By (stage, round field).
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint64_t> bytes_per_stage_round;
  /// CPU time of each agent's message handling, by the handled message's (stage, round) and
  /// agent. Agents run one after another here but concurrently over the network, where a round
  /// lasts as long as its slowest agent: `critical_path_cpu_s` = sum over (stage, round) of the
  /// largest agent's CPU time, an estimate of the distributed run's compute time (no latency)
  /// that does not depend on how many agents share this process or the machine's load. A
  /// message's time includes the driver's queueing just before it (the receiving side's share
  /// of a transport).
  double critical_path_cpu_s = 0.0;
  /// The longest chain of messages each sent by the previous one's recipient after it handled
  /// it: message steps the run waits through one after another whatever the network, a count
  /// the protocols' own message-step figures (two a round, ...) can be checked against.
  std::uint64_t longest_chain = 0;
};

/// Bytes of a message's content as it would travel: every field of the core message at its
/// own width (a status: 4 x 4-byte ids and counts, 3 doubles, 2 one-byte votes = 42 bytes)
/// plus its arrays' elements. Transport-independent, so an in-process run and a DDS run count
/// the same traffic (the DDS agents' certificate_bytes / escape_bytes use it too). A DDS
/// sample is larger: it adds the run id, routing (broadcast, recipients), the rollback epoch,
/// its own fields (a status's bundle and riding blocks), sequence lengths and CDR padding,
/// which the DDS runtime counts in bytes_sent (transport/message_mapping.hpp serialized_size).
std::size_t message_bytes(const ProtocolMessage& message);

/// Delivers messages until every agent is done (or no message is left, which would be a
/// protocol bug: then std::logic_error). `agents[i]` must be the agent with id i.
/// `threads` > 1 (kFifo only; other orders run on one thread): the agents handle their messages
/// on that many threads, in waves (all messages queued now, before those they cause), which is
/// exactly the FIFO order per agent: the same iterates as one thread. The agents must share no
/// mutable state (each holds its own block and factors).
DeliveryStats run_in_process(const std::vector<AgentProcess*>& agents, DeliveryOrder order,
                             std::uint64_t delivery_seed = 1, int threads = 1);
/// Same for plain round protocols.
DeliveryStats run_in_process(const std::vector<RoundProtocol*>& agents, DeliveryOrder order,
                             std::uint64_t delivery_seed = 1);

/// Same, but every agent continues from its snapshot (`snapshots[i]` for agent i, all of the
/// same round) instead of starting: a coordinated rollback in one process.
DeliveryStats resume_in_process(const std::vector<RoundProtocol*>& agents,
                                const std::vector<ProtocolSnapshot>& snapshots, DeliveryOrder order,
                                std::uint64_t delivery_seed = 1);

}  // namespace tessera
