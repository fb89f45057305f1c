#include <algorithm>
#include <ctime>
#include <deque>
#include <functional>
#include <stdexcept>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/distributed/stage_tag.hpp>

#include "distributed/wave_pool.hpp"

namespace tessera {

namespace {

template <class T>
std::size_t array_bytes(const std::vector<T>& values) {
  return values.size() * sizeof(T);
}

}  // namespace

// Every field by name: the bindings compile only while they name all of the message's fields,
// so a field added to a message must be counted here too.
std::size_t message_bytes(const ProtocolMessage& message) {
  if (const auto* p = std::get_if<PoseBlockMessage>(&message)) {
    const auto& [round, sender, phase, kind, rank, dim, pose_ids, data] = *p;
    return sizeof(round) + sizeof(sender) + sizeof(phase) + sizeof(kind) + sizeof(rank) +
           sizeof(dim) + array_bytes(pose_ids) + array_bytes(data);
  }
  const auto& [round, sender, phase, cost, grad_norm_sq, block_grad_norm, restart_vote, done_vote,
               near_bound, coarse, measurement_ids, weights] =
      std::get<RoundStatusMessage>(message);
  return sizeof(round) + sizeof(sender) + sizeof(phase) + sizeof(cost) + sizeof(grad_norm_sq) +
         sizeof(block_grad_norm) + sizeof(restart_vote) + sizeof(done_vote) + sizeof(near_bound) +
         array_bytes(coarse) + array_bytes(measurement_ids) + array_bytes(weights);
}

namespace {

struct Delivery {
  std::size_t recipient;
  ProtocolMessage message;
  std::uint64_t chain = 0;  // its place in the longest chain of messages that led to it
};

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::uint32_t round_of(const ProtocolMessage& m) {
  if (const auto* p = std::get_if<PoseBlockMessage>(&m)) return p->round;
  return std::get<RoundStatusMessage>(m).round;
}

DeliveryStats deliver(const std::vector<AgentProcess*>& agents, DeliveryOrder order,
                      std::uint64_t delivery_seed, int threads,
                      const std::function<std::vector<OutgoingMessage>(std::size_t)>& begin) {
  DeliveryStats stats;
  std::deque<Delivery> queue;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<double>> cpu;
  const std::size_t n = agents.size();
  // The longest chain of messages each agent has handled (DeliveryStats::longest_chain).
  std::vector<std::uint64_t> chain(n, 0);
  // CPU seconds of one handled message, charged to its recipient in the message's (stage, round).
  auto charge = [&](const ProtocolMessage& message, std::size_t recipient, double seconds) {
    auto& per_agent = cpu[{stage_of_phase(message_phase(message)), round_of(message)}];
    if (per_agent.empty()) per_agent.assign(n, 0.0);
    per_agent[recipient] += seconds;
  };
  // `after`: the sender's chain when it sent them.
  auto post = [&](std::size_t sender, std::vector<OutgoingMessage>&& out, std::uint64_t after) {
    for (auto& o : out) {
      const std::size_t bytes = message_bytes(o.message);
      const std::uint32_t round = round_of(o.message);
      const std::uint32_t stage = stage_of_phase(message_phase(o.message));
      // The last recipient takes the message itself, the others a copy: a CG iteration's pose
      // blocks and coarse sums were copied once more than delivered.
      auto count = [&](std::size_t recipient, bool last) {
        ++stats.messages;
        stats.bytes += bytes;
        if (stats.bytes_per_round.size() <= round) stats.bytes_per_round.resize(round + 1, 0);
        stats.bytes_per_round[round] += bytes;
        if (stats.bytes_per_stage.size() <= stage) stats.bytes_per_stage.resize(stage + 1, 0);
        stats.bytes_per_stage[stage] += bytes;
        stats.bytes_per_stage_round[{stage, round}] += bytes;
        if (last)
          queue.push_back({recipient, std::move(o.message), after + 1});
        else
          queue.push_back({recipient, o.message, after + 1});
      };
      if (o.broadcast) {
        const std::size_t final_recipient = sender + 1 < n ? n - 1 : n - 2;
        for (std::size_t r = 0; r < n; ++r)
          if (r != sender) count(r, r == final_recipient);
      } else {
        for (std::size_t k = 0; k < o.recipients.size(); ++k)
          count(o.recipients[k], k + 1 == o.recipients.size());
      }
    }
  };
  if (order == DeliveryOrder::kReversed) {
    for (std::size_t i = n; i-- > 0;) post(i, begin(i), 0);
  } else {
    for (std::size_t i = 0; i < n; ++i) post(i, begin(i), 0);
  }
  std::uint64_t state = delivery_seed * 0x9E3779B97F4A7C15ull + 1;
  auto next_random = [&] {  // xorshift64*: reproducible and cheap
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 0x2545F4914F6CDD1Dull;
  };
  // Each delivery's CPU time is read once, at its end: the interval since the previous reading
  // (the driver's queueing of the previous outputs, then this handle()) is charged to this
  // recipient. Two clock reads per delivery were ~4 % of a short solve's CPU (the thread clock is
  // a system call), and most deliveries only buffer a status message.
  if (threads > 1 && order == DeliveryOrder::kFifo && n > 1) {
    // FIFO in waves: the messages queued now are handled before any they cause (their outputs
    // are queued behind all of them), so a wave's deliveries to different agents are
    // independent. Each agent handles its own in queue order on one thread, and the outputs are
    // queued in the wave's order: the same deliveries, in the same order per agent, as one
    // thread gives, hence the same iterates.
    WavePool pool(std::min<int>(threads, static_cast<int>(n)));
    std::vector<std::vector<std::size_t>> mine(n);
    std::vector<Delivery> wave;
    std::vector<std::vector<OutgoingMessage>> outs;
    std::vector<double> took;          // < 0: not handled (agent done)
    std::vector<std::uint64_t> after;  // the recipient's chain once it handled the delivery
    while (!queue.empty()) {
      wave.assign(std::make_move_iterator(queue.begin()), std::make_move_iterator(queue.end()));
      queue.clear();
      for (auto& m : mine) m.clear();
      for (std::size_t k = 0; k < wave.size(); ++k) {
        if (wave[k].recipient >= n)
          throw std::logic_error("in-process driver: message to unknown agent");
        mine[wave[k].recipient].push_back(k);
      }
      outs.assign(wave.size(), {});
      took.assign(wave.size(), -1.0);
      after.assign(wave.size(), 0);
      pool.run(n, [&](std::size_t r) {
        double t0 = thread_cpu_s();
        for (std::size_t k : mine[r]) {
          if (agents[r]->done()) continue;
          outs[k] = agents[r]->handle(wave[k].message);
          chain[r] = std::max(chain[r], wave[k].chain);  // this thread's agent only
          after[k] = chain[r];
          const double t1 = thread_cpu_s();
          took[k] = t1 - t0;
          t0 = t1;
        }
      });
      for (std::size_t k = 0; k < wave.size(); ++k) {
        if (took[k] < 0) continue;
        charge(wave[k].message, wave[k].recipient, took[k]);
        post(wave[k].recipient, std::move(outs[k]), after[k]);
      }
    }
  }
  double t_prev = thread_cpu_s();
  while (!queue.empty()) {
    Delivery d;
    if (order == DeliveryOrder::kFifo) {
      d = std::move(queue.front());
      queue.pop_front();
    } else if (order == DeliveryOrder::kReversed) {
      d = std::move(queue.back());
      queue.pop_back();
    } else {
      const std::size_t k = static_cast<std::size_t>(next_random() % queue.size());
      std::swap(queue[k], queue.back());
      d = std::move(queue.back());
      queue.pop_back();
    }
    if (d.recipient >= n) throw std::logic_error("in-process driver: message to unknown agent");
    if (agents[d.recipient]->done()) continue;
    std::vector<OutgoingMessage> out = agents[d.recipient]->handle(d.message);
    chain[d.recipient] = std::max(chain[d.recipient], d.chain);
    const double t = thread_cpu_s();
    charge(d.message, d.recipient, t - t_prev);
    t_prev = t;
    post(d.recipient, std::move(out), chain[d.recipient]);
  }
  stats.longest_chain = *std::max_element(chain.begin(), chain.end());
  for (const auto& [slot, per_agent] : cpu)
    stats.critical_path_cpu_s += *std::max_element(per_agent.begin(), per_agent.end());
  for (auto* a : agents)
    if (!a->done())
      throw std::logic_error("in-process driver: agents stalled with no message in flight");
  return stats;
}

}  // namespace

DeliveryStats run_in_process(const std::vector<AgentProcess*>& agents, DeliveryOrder order,
                             std::uint64_t delivery_seed, int threads) {
  return deliver(agents, order, delivery_seed, threads,
                 [&](std::size_t i) { return agents[i]->start(); });
}

DeliveryStats run_in_process(const std::vector<RoundProtocol*>& agents, DeliveryOrder order,
                             std::uint64_t delivery_seed) {
  return run_in_process(std::vector<AgentProcess*>(agents.begin(), agents.end()), order,
                        delivery_seed);
}

DeliveryStats resume_in_process(const std::vector<RoundProtocol*>& agents,
                                const std::vector<ProtocolSnapshot>& snapshots, DeliveryOrder order,
                                std::uint64_t delivery_seed) {
  if (snapshots.size() != agents.size())
    throw std::invalid_argument("resume_in_process: one snapshot per agent needed");
  for (const auto& s : snapshots)
    if (s.round != snapshots.front().round)
      throw std::invalid_argument("resume_in_process: snapshots of different rounds");
  const std::vector<AgentProcess*> processes(agents.begin(), agents.end());
  return deliver(processes, order, delivery_seed, 1,
                 [&](std::size_t i) { return agents[i]->resume(snapshots[i]); });
}

}  // namespace tessera
