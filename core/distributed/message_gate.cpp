#include <algorithm>
#include <stdexcept>
#include <tessera/distributed/message_gate.hpp>

namespace tessera {

void MessageGate::expect(std::uint32_t round, std::uint32_t step, std::vector<int> senders) {
  round_ = round;
  step_ = step;
  senders_ = std::move(senders);
}

bool MessageGate::add(int sender, std::uint32_t round, std::uint32_t step,
                      ProtocolMessage message) {
  return pending_[key(round, step)].emplace(sender, std::move(message)).second;
}

std::optional<MessageGate::Inbox> MessageGate::take_ready() {
  auto it = pending_.find(key(round_, step_));
  if (senders_.empty()) {
    Inbox none;
    if (it != pending_.end()) {
      none = std::move(it->second);
      pending_.erase(it);
    }
    return none;
  }
  if (it == pending_.end()) return std::nullopt;
  for (int s : senders_)
    if (!it->second.count(s)) return std::nullopt;
  Inbox ready = std::move(it->second);
  pending_.erase(it);
  return ready;
}

std::vector<int> MessageGate::missing() const {
  const auto it = pending_.find(key(round_, step_));
  std::vector<int> out;
  for (int s : senders_)
    if (it == pending_.end() || !it->second.count(s)) out.push_back(s);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<ProtocolMessage> MessageGate::take_steps(std::uint32_t first, std::uint32_t last) {
  // The map is ordered by round first; collect the steps' entries, then order them by step.
  std::vector<std::pair<std::uint64_t, Inbox>> taken;
  for (auto it = pending_.begin(); it != pending_.end();) {
    const std::uint32_t step = step_of(it->first);
    if (step < first || step >= last) {
      ++it;
      continue;
    }
    taken.emplace_back(it->first, std::move(it->second));
    it = pending_.erase(it);
  }
  std::stable_sort(taken.begin(), taken.end(), [](const auto& a, const auto& b) {
    return step_of(a.first) < step_of(b.first);
  });
  std::vector<ProtocolMessage> out;
  for (auto& [k, inbox] : taken)
    for (auto& [sender, m] : inbox) out.push_back(std::move(m));
  return out;
}

PoseBlockMessage make_reduction_message(int sender, std::uint32_t round, std::uint32_t phase,
                                        const std::vector<double>& values) {
  PoseBlockMessage m;
  m.round = round;
  m.sender = static_cast<std::uint32_t>(sender);
  m.phase = phase;
  m.kind = BlockKind::kY;
  m.rank = 1;
  m.dim = 0;
  m.pose_ids.resize(values.size());
  for (std::size_t k = 0; k < values.size(); ++k) m.pose_ids[k] = static_cast<std::uint32_t>(k);
  m.data = values;
  return m;
}

const std::vector<double>& reduction_values(const ProtocolMessage& message, std::size_t count) {
  const auto* p = std::get_if<PoseBlockMessage>(&message);
  if (!p || p->data.size() != count || p->rank != 1 || p->dim != 0)
    throw std::runtime_error("reduction message from agent " +
                             std::to_string(message_sender(message)) + " does not hold " +
                             std::to_string(count) + " values");
  return p->data;
}

std::vector<double> reduce_in_id_order(const MessageGate::Inbox& inbox, std::size_t count,
                                       const std::vector<std::size_t>& max_entries) {
  std::vector<double> total(count, 0.0);
  bool first = true;
  for (const auto& [sender, m] : inbox) {
    const auto& v = reduction_values(m, count);
    if (max_entries.empty()) {  // plain sums (a coarse matrix sum carries tens of thousands)
      for (std::size_t k = 0; k < count; ++k) total[k] += v[k];
      continue;
    }
    for (std::size_t k = 0; k < count; ++k) {
      const bool is_max = std::find(max_entries.begin(), max_entries.end(), k) != max_entries.end();
      if (is_max)
        total[k] = first ? v[k] : std::max(total[k], v[k]);
      else
        total[k] += v[k];
    }
    first = false;
  }
  return total;
}

std::uint32_t message_round(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.round; }, m);
}
std::uint32_t message_sender(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.sender; }, m);
}
std::uint32_t message_phase(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.phase; }, m);
}

}  // namespace tessera
