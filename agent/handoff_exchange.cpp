#include "agent/handoff_exchange.hpp"

#include <deque>
#include <set>

#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

std::vector<ReceivedHandoff> exchange_handoffs(AgentSession& s, const RobotShare& share,
                                               const std::vector<std::uint32_t>& owner,
                                               std::uint32_t self, std::uint32_t robots,
                                               const std::string& run_id, double timeout_s) {
  for (std::uint32_t b = 0; b < robots; ++b) {
    if (b == self) continue;
    HandoffPlan plan = plan_handoff(share, owner, b);
    s.publish(to_wire_handoff(run_id, self, b, share.d, plan.measurements, plan.measurement_index,
                              plan.poses, plan.known_poses));
  }
  const std::size_t others = robots - 1;
  auto senders_missing = [&](const std::deque<wire::MeasurementHandoff>& q) {
    std::set<std::uint32_t> have;
    for (const auto& h : q) have.insert(h.sender());
    std::string out;
    for (std::uint32_t b = 0; b < robots; ++b)
      if (b != self && !have.count(b))
        out += (out.empty() ? "agent " : ", agent ") + std::to_string(b);
    return out;
  };
  std::string absent;
  expect_ready(s.handoffs().wait_for(
                   [&](const auto& q) {
                     absent = senders_missing(q);
                     return q.size() >= others && absent.empty();
                   },
                   Seconds(timeout_s)),
               s.mailroom(), timeout_s, "measurement hand-offs", "none yet from " + absent);
  std::vector<ReceivedHandoff> received;
  for (auto& w : s.handoffs().take_all()) {
    HandoffContent c = from_wire(w);
    received.push_back({w.sender(), std::move(c.measurements), std::move(c.measurement_index),
                        std::move(c.poses), std::move(c.known_poses)});
  }
  return received;
}

}  // namespace tessera::agent
