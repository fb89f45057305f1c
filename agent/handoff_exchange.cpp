#include "agent/handoff_exchange.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <map>
#include <set>

#include "transport/addressed_filter.hpp"
#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

namespace {

// A part's size: 160 measurements and poses in 3D, with a robust run's second start for those
// poses (128 B a measurement, 100 B a pose, 100 B its second start), under
// kMaxAddressedSampleBytes, so each part is one transport message that the writer filters for
// its recipient.
constexpr std::size_t kPartBytes = 160 * 328;

// Measurements and poses per part in dimension d: as many as fill kPartBytes (3D: 160; 2D:
// 285, so that a 2D hand-off is not cut into 1.8 times as many parts, each a message and
// the whole a few more waits for acknowledgements below).
std::size_t items_per_part(int d) {
  const auto flat_pose = static_cast<std::size_t>(8 * d * (d + 1));  // [R | t]
  const std::size_t measurement = 8 + 4 + 4 + flat_pose + 8 + 8;  // index, i, j, R, t, kappa, tau
  const std::size_t pose = 4 + flat_pose;                         // id, [R | t]
  return kPartBytes / (measurement + 2 * pose);
}

// Parts written before the agent waits for them to be acknowledged (~850 KB): every agent
// hands off at once, so without a bound each writer has up to its whole history (256 parts,
// ~13 MB) in flight; 64 agents over UDP on one host overflowed the receivers' socket buffers,
// and the repairs of what was dropped were dropped in turn.
constexpr std::size_t kPartsInFlight = 16;

template <class T>
std::vector<T> slice(const std::vector<T>& v, std::size_t begin, std::size_t count) {
  begin = std::min(begin, v.size());
  const std::size_t end = std::min(v.size(), begin + count);
  return std::vector<T>(v.begin() + static_cast<std::ptrdiff_t>(begin),
                        v.begin() + static_cast<std::ptrdiff_t>(end));
}

// Whether every part of every other agent's hand-off is in `q`; names the missing senders.
bool complete(const std::deque<wire::MeasurementHandoff>& q, std::uint32_t self,
              std::uint32_t robots, std::string* absent) {
  std::map<std::uint32_t, std::set<std::uint32_t>> parts_of;
  std::map<std::uint32_t, std::uint32_t> expected;
  for (const auto& h : q) {
    parts_of[h.sender()].insert(h.part());
    expected[h.sender()] = std::max<std::uint32_t>(1, h.parts());
  }
  absent->clear();
  for (std::uint32_t b = 0; b < robots; ++b) {
    if (b == self) continue;
    auto it = parts_of.find(b);
    if (it == parts_of.end() || it->second.size() < expected[b])
      *absent += (absent->empty() ? "agent " : ", agent ") + std::to_string(b);
  }
  return absent->empty();
}

}  // namespace

std::vector<ReceivedHandoff> exchange_handoffs(AgentSession& s, const RobotShare& share,
                                               const std::vector<std::uint32_t>& owner,
                                               std::uint32_t self, std::uint32_t robots,
                                               const std::string& run_id, double timeout_s,
                                               HandoffSending* sending) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  HandoffSending sent;
  const auto send_start = Clock::now();
  std::size_t unacknowledged = 0;
  const std::size_t per_part = items_per_part(share.d);
  for (std::uint32_t b = 0; b < robots; ++b) {
    if (b == self) continue;
    const HandoffPlan plan = plan_handoff(share, owner, b);
    const std::size_t items =
        std::max({plan.measurements.size(), plan.poses.size(), plan.known_poses.size()});
    const std::size_t parts = std::max<std::size_t>(1, (items + per_part - 1) / per_part);
    for (std::size_t p = 0; p < parts; ++p) {
      const std::size_t at = p * per_part;
      wire::MeasurementHandoff w =
          to_wire_handoff(run_id, self, b, share.d, slice(plan.measurements, at, per_part),
                          slice(plan.measurement_index, at, per_part),
                          slice(plan.poses, at, per_part), slice(plan.known_poses, at, per_part));
      w.part(static_cast<std::uint32_t>(p));
      w.parts(static_cast<std::uint32_t>(parts));
      // The hand-off's own bound, not a network step's 30 s: an agent sends thousands of parts
      // to peers that may still be computing on a loaded host (64 agents at load 65-115: not
      // acknowledged in 30 s); a dead peer frees the history when its lease expires.
      s.publish(w, timeout_s);
      ++sent.parts;
      if (++unacknowledged == kPartsInFlight) {
        // Not acknowledged in time: go on; the write then waits for room as before.
        const auto wait_start = Clock::now();
        (void)s.handoffs_acknowledged(Seconds(std::min(timeout_s, 30.0)));
        sent.ack_wait_s += seconds_since(wait_start);
        unacknowledged = 0;
      }
    }
  }
  sent.send_s = seconds_since(send_start);
  if (sending) *sending = sent;
  std::string absent;
  expect_ready(
      s.handoffs().wait_for([&](const auto& q) { return complete(q, self, robots, &absent); },
                            Seconds(timeout_s)),
      s.mailroom(), timeout_s, "measurement hand-offs", "none complete yet from " + absent);
  // One hand-off per sender, its parts in order (so its measurements keep the sender's order).
  std::map<std::uint32_t, std::map<std::uint32_t, wire::MeasurementHandoff>> by_sender;
  for (auto& w : s.handoffs().take_all()) {
    const std::uint32_t sender = w.sender(), part = w.part();
    by_sender[sender].emplace(part, std::move(w));
  }
  std::vector<ReceivedHandoff> received;
  for (auto& [sender, parts] : by_sender) {
    ReceivedHandoff r{sender, {}, {}, {}, {}};
    for (auto& [part, w] : parts) {
      HandoffContent c = from_wire(w);
      r.measurements.insert(r.measurements.end(), std::make_move_iterator(c.measurements.begin()),
                            std::make_move_iterator(c.measurements.end()));
      r.measurement_index.insert(r.measurement_index.end(), c.measurement_index.begin(),
                                 c.measurement_index.end());
      r.poses.insert(r.poses.end(), std::make_move_iterator(c.poses.begin()),
                     std::make_move_iterator(c.poses.end()));
      r.known_poses.insert(r.known_poses.end(), std::make_move_iterator(c.known_poses.begin()),
                           std::make_move_iterator(c.known_poses.end()));
      w = wire::MeasurementHandoff();  // decoded: free its arrays now
    }
    received.push_back(std::move(r));
  }
  return received;
}

}  // namespace tessera::agent
