#include "agent/survivor_exchange.hpp"

#include <algorithm>
#include <set>
#include <string>

#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

namespace {

wire::MeasurementHandoff encode(const std::string& run_id, std::uint32_t sender,
                                std::uint32_t recipient, int d, std::uint8_t purpose,
                                std::uint32_t epoch, std::uint32_t round,
                                const std::vector<Measurement>& measurements,
                                const std::vector<std::uint64_t>& index, std::uint32_t rank,
                                const std::vector<std::uint32_t>& lifted_ids,
                                const std::vector<double>& lifted_data) {
  std::vector<const Measurement*> ptrs;
  for (const auto& m : measurements) ptrs.push_back(&m);
  wire::MeasurementHandoff w = to_wire_handoff(run_id, sender, recipient, d, ptrs, index, {});
  w.purpose(purpose);
  w.epoch(epoch);
  w.round(round);
  w.rank(rank);
  w.lifted_ids(lifted_ids);
  w.lifted_data(lifted_data);
  return w;
}

}  // namespace

void send_problem_replicas(AgentSession& session, const AgentLocalData& local, std::uint32_t self,
                           const Eigen::MatrixXd& Y0, const std::vector<std::uint32_t>& holders) {
  const std::vector<double> data(Y0.data(), Y0.data() + Y0.size());
  for (std::uint32_t h : holders)
    session.publish(encode(session.options().run_id, self, h, local.d, 1, 0, 0, local.measurements,
                           local.measurement_index, static_cast<std::uint32_t>(Y0.rows()),
                           local.owned, data));
}

void absorb_problem_replicas(AgentSession& session, ReplicaStore& store) {
  for (auto& w : session.replicas().take_all()) {
    HandoffContent c = from_wire(w);
    const std::size_t width = static_cast<std::size_t>(w.rank()) * (w.dim() + 1);
    store.absorb_problem(w.sender(), std::move(c.measurements), std::move(c.measurement_index),
                         w.lifted_ids(), w.lifted_data(), width, w.round());
  }
}

Reassignment reassignment_of(const wire::PartitionAssignment& a,
                             const std::vector<std::uint32_t>& old_owner) {
  Reassignment r;
  r.epoch = a.epoch();
  r.old_owner = old_owner;
  r.new_owner = a.owner();
  r.survivors = a.survivors();
  r.lost = a.lost();
  if (r.new_owner.size() != old_owner.size() || r.survivors.empty() || r.lost.empty() ||
      !std::is_sorted(r.survivors.begin(), r.survivors.end()))
    throw RunFailure(kExitRunFailed, "the coordinator's re-partition (epoch " +
                                         std::to_string(r.epoch) + ") is malformed");
  return r;
}

AgentLocalData exchange_takeover(AgentSession& session, const TakeoverSource& src,
                                 const Reassignment& r, double timeout_s) {
  const int d = src.local->d;
  const auto rank = static_cast<std::uint32_t>(src.Y.rows());
  for (std::uint32_t b : r.survivors) {
    if (b == src.self) continue;
    const TakeoverMessage t = plan_takeover(src, r, b);
    session.publish(encode(session.options().run_id, src.self, b, d, 2, r.epoch, t.round,
                           t.measurements, t.measurement_index, rank, t.lifted_ids, t.lifted_data));
  }
  // One take-over from every other survivor, of this epoch (older hand-offs are dropped).
  std::set<std::uint32_t> have;
  std::vector<TakeoverMessage> received;
  std::string missing;
  auto collect = [&]() {
    for (auto& w : session.handoffs().take_all()) {
      if (w.purpose() != 2 || w.epoch() != r.epoch || have.count(w.sender())) continue;
      HandoffContent c = from_wire(w);
      TakeoverMessage t;
      t.sender = w.sender();
      t.measurements = std::move(c.measurements);
      t.measurement_index = std::move(c.measurement_index);
      t.lifted_ids = w.lifted_ids();
      t.lifted_data = w.lifted_data();
      t.round = w.round();
      have.insert(t.sender);
      received.push_back(std::move(t));
    }
    missing.clear();
    for (std::uint32_t b : r.survivors)
      if (b != src.self && !have.count(b))
        missing += (missing.empty() ? "agent " : ", agent ") + std::to_string(b);
    return missing.empty();
  };
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(timeout_s));
  while (!collect()) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    const WaitStatus st = session.handoffs().wait_for([](const auto& q) { return !q.empty(); },
                                                      Seconds(std::max(0.0, std::min(left, 0.5))));
    if (st == WaitStatus::kStopped) {
      const auto stop = session.mailroom().stop_info();
      throw RunFailure(stop ? stop->exit_code : kExitRunFailed, stop ? stop->reason : "stopped",
                       false);
    }
    if (left <= 0)
      throw RunFailure(kExitRunFailed, "take-over after the re-partition: no message for " +
                                           std::to_string(timeout_s) + " s from " + missing);
  }
  return assemble_takeover(src, r, received);
}

}  // namespace tessera::agent
