#pragma once
// Helpers of the tests that open DDS sessions of several roles in one process (a coordinator
// and agents, each a session of its own): their options, readiness as separate processes reach
// it, the messages they send and what an agent's session received.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <future>
#include <memory>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "transport/agent_session.hpp"
#include "transport/session.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport::test {

/// The options of the coordinator's session (`coordinator`) or agent `agent`'s in run `run_id`
/// of `agents` agents on `domain`, with participant lease `lease_s` (long enough that a loaded
/// machine does not make a live peer lost).
inline SessionOptions session_options(const std::string& run_id, int domain, bool coordinator,
                                      std::uint32_t agent, std::uint32_t agents, double lease_s) {
  SessionOptions o;
  o.run_id = run_id;
  o.domain = domain;
  o.coordinator = coordinator;
  o.agent_id = agent;
  o.num_agents = agents;
  o.lease_s = lease_s;
  return o;
}

/// Agent 0's pose block of round 7 and `phase` (rank 2, d 1: 4 values a pose) with poses
/// `ids` and values `data`, to `recipients` (none: a broadcast).
inline OutgoingMessage pose_block_to(std::vector<std::uint32_t> recipients, std::uint32_t phase,
                                     std::vector<std::uint32_t> ids, std::vector<double> data) {
  PoseBlockMessage b;
  b.round = 7;
  b.sender = 0;
  b.phase = phase;
  b.rank = 2;
  b.dim = 1;
  b.pose_ids = std::move(ids);
  b.data = std::move(data);
  OutgoingMessage m;
  m.message = b;
  m.broadcast = recipients.empty();
  m.recipients = std::move(recipients);
  return m;
}

/// Every session passes the readiness barrier (every endpoint matched, READY from all), all at
/// once as separate processes would, each within `timeout`.
inline void pass_readiness_barriers(std::vector<std::unique_ptr<Session>>& sessions,
                                    Seconds timeout) {
  std::vector<std::future<WaitStatus>> barriers;
  for (auto& s : sessions)
    barriers.push_back(std::async(std::launch::async, [&s, timeout] {
      std::string missing;
      return s->ready_barrier(timeout, &missing);
    }));
  for (auto& b : barriers) ASSERT_EQ(b.get(), WaitStatus::kReady);
}

/// The phases of the protocol messages `s` has received, in arrival order per type: `expected`
/// of them, or fewer after 10 s.
inline std::vector<std::uint32_t> received_phases(AgentSession& s, std::size_t expected) {
  std::vector<std::uint32_t> out;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (out.size() < expected && std::chrono::steady_clock::now() < until) {
    ProtocolMessage m;
    if (s.protocol().take(Seconds(0.2), &m) == WaitStatus::kReady)
      out.push_back(std::visit([](const auto& x) { return x.phase; }, m));
  }
  return out;
}

}  // namespace tessera::transport::test
