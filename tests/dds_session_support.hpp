#pragma once
// Helpers of the tests that open DDS sessions of several roles in one process (a coordinator
// and agents, each a session of its own): readiness as separate processes reach it, and what an
// agent's session received.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <future>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "transport/agent_session.hpp"
#include "transport/session.hpp"

namespace tessera::transport::test {

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
