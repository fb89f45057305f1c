#include "agent/lost_for_good.hpp"

#include <algorithm>

namespace tessera::agent {

LostForGood::LostForGood(std::uint32_t agent_id, const std::string& run_id, std::uint32_t epoch)
    : cli::LeaveAlone(transport::kExitRunFailed,
                      "agent " + std::to_string(agent_id) + " was lost for good in run '" + run_id +
                          "': its block was re-partitioned among the survivors (epoch " +
                          std::to_string(epoch) +
                          "), so it cannot rejoin; the run goes on without it") {}

std::optional<std::uint32_t> epoch_that_lost(const wire::PartitionAssignment& a,
                                             std::uint32_t agent_id) {
  const auto& lost = a.lost();
  if (std::find(lost.begin(), lost.end(), agent_id) == lost.end()) return std::nullopt;
  return a.epoch();
}

void refuse_if_lost(const wire::PartitionAssignment& a, std::uint32_t agent_id,
                    const std::string& run_id) {
  if (auto e = epoch_that_lost(a, agent_id)) throw LostForGood(agent_id, run_id, *e);
}

void refuse_if_lost(transport::AgentSession& session, std::uint32_t agent_id) {
  auto& inbox = session.assignments();
  const std::optional<wire::PartitionAssignment> losing =
      session.mailroom().with_lock([&]() -> std::optional<wire::PartitionAssignment> {
        for (const auto& a : inbox.queued_locked())
          if (epoch_that_lost(a, agent_id)) return a;
        return std::nullopt;
      });
  if (losing) refuse_if_lost(*losing, agent_id, losing->run_id());
}

}  // namespace tessera::agent
