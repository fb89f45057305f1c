#pragma once
// The messages an agent's current protocol step still lacks, by name: one (round, phase) and
// the senders whose message of it has not come yet. A driver that knows them can sleep until
// exactly those have arrived; a count (AgentProcess::messages_needed) cannot tell them from
// messages of later steps (e.g. a neighbour's block and its next status), so it wakes early.

#include <cstdint>
#include <tessera/protocol/messages.hpp>
#include <variant>
#include <vector>

namespace tessera {

struct AwaitedMessages {
  std::uint32_t round = 0;
  std::uint32_t phase = 0;  ///< As on the wire (stage-tagged for the certified sequence).
  std::vector<std::uint32_t> senders;  ///< Still missing, ascending.
};

/// Whether `m` is one of the awaited messages.
inline bool is_awaited(const AwaitedMessages& a, const ProtocolMessage& m) {
  return std::visit(
      [&](const auto& x) {
        if (x.round != a.round || x.phase != a.phase) return false;
        for (auto s : a.senders)
          if (s == x.sender) return true;
        return false;
      },
      m);
}

/// Whether `queued` holds a message of every awaited sender.
template <class Range>
bool all_awaited_in(const AwaitedMessages& a, const Range& queued) {
  for (auto s : a.senders) {
    bool found = false;
    for (const ProtocolMessage& m : queued) {
      found = std::visit(
          [&](const auto& x) { return x.round == a.round && x.phase == a.phase && x.sender == s; },
          m);
      if (found) break;
    }
    if (!found) return false;
  }
  return true;
}

}  // namespace tessera
