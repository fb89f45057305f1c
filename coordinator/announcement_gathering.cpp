#include "coordinator/announcement_gathering.hpp"

#include <deque>
#include <set>

#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

std::vector<wire::AgentAnnouncement> await_announcements(CoordinatorSession& session,
                                                         std::uint32_t num_agents,
                                                         const std::string& run_id,
                                                         double timeout_s) {
  const std::uint32_t N = num_agents;
  std::string missing;
  auto all_announced = [&](const std::deque<wire::AgentAnnouncement>& q) {
    std::set<std::uint32_t> have;
    for (const auto& m : q) {
      if (m.agent_id() >= N || m.num_agents() != N) return true;  // let merge_announcements explain
      have.insert(m.agent_id());
    }
    missing.clear();
    std::string present;
    for (std::uint32_t k = 0; k < N; ++k) {
      std::string& list = have.count(k) ? present : missing;
      list += (list.empty() ? "" : ", ") + std::to_string(k);
    }
    if (!missing.empty())
      missing =
          "missing agent " + missing + (present.empty() ? "" : " (have agent " + present + ")");
    return have.size() == N;
  };
  expect_ready(session.announcements().wait_for(all_announced, Seconds(timeout_s)),
               session.mailroom(), timeout_s,
               std::to_string(N) + " agents of run '" + run_id + "' on domain " +
                   std::to_string(session.domain()),
               missing);
  return session.announcements().take_all();
}

}  // namespace tessera::coordinator
