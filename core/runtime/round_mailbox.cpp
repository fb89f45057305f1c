#include "runtime/round_mailbox.hpp"

#include <algorithm>
#include <chrono>
#include <tessera/distributed/in_process_driver.hpp>

#include "runtime/initialization_stage.hpp"

namespace tessera::agent {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void Mailbox::send_all(const std::vector<OutgoingMessage>& out) {
  const auto t0 = std::chrono::steady_clock::now();
  channel_.send_all(out);
  for (const auto& m : out) {
    // Certificate and escape traffic, as the in-process driver counts it (per delivery).
    const std::uint32_t phase = phase_of(m.message);
    if (is_auxiliary_phase(phase)) continue;
    const StageKind kind = stage_kind(stage_of_phase(phase));
    if (kind == StageKind::kSolve) continue;
    const std::uint64_t copies = m.broadcast ? num_agents_ - 1 : m.recipients.size();
    (kind == StageKind::kCertify ? certificate_bytes : escape_bytes) +=
        copies * message_bytes(m.message);
  }
  send_s += seconds_since(t0);
  sent_since_gather_ = true;
}

std::optional<ProtocolMessage> Mailbox::receive(std::size_t wake_after) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<ProtocolMessage> msg = wake_after > 1
                                           ? channel_.receive_after(timeout_s_, wake_after)
                                           : channel_.receive(timeout_s_);
  wait_s += seconds_since(t0);
  return msg;
}

std::optional<ProtocolMessage> Mailbox::receive(const AwaitedMessages& awaited) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<ProtocolMessage> msg = channel_.receive_awaiting(timeout_s_, awaited);
  wait_s += seconds_since(t0);
  return msg;
}

std::map<std::uint32_t, ProtocolMessage> Mailbox::gather(
    std::uint32_t phase, std::uint32_t round, const std::vector<std::uint32_t>& senders) {
  const auto key = std::make_pair(phase, round);
  for (;;) {
    auto& have = stash_[key];
    AwaitedMessages awaited{round, phase, {}};
    for (auto s : senders)
      if (!have.count(s)) awaited.senders.push_back(s);
    if (awaited.senders.empty()) break;
    std::sort(awaited.senders.begin(), awaited.senders.end());
    // Sleep until the missing senders' messages have come, not once per message: a reduction
    // waits for every other agent's status, and each wake-up of this thread costs more than
    // handling a small message (as run_protocol's steps; docs/dds-runtime.md, "Round waits").
    std::optional<ProtocolMessage> msg = receive(awaited);
    if (!msg) {
      std::string who;
      for (auto s : senders)
        if (!stash_[key].count(s)) who += " " + std::to_string(s);
      throw std::runtime_error("agent " + std::to_string(self_) + ": rounding step " +
                               std::to_string(phase) + " (iteration " + std::to_string(round) +
                               "): nothing received for " + std::to_string(timeout_s_) +
                               " s; waiting for agent(s)" + who);
    }
    if (!is_auxiliary_phase(phase_of(*msg))) continue;  // late protocol traffic
    keep(std::move(*msg));
  }
  auto out = std::move(stash_[key]);
  stash_.erase(key);
  if (sent_since_gather_) ++gathers;  // the first wait after sending: one message step
  sent_since_gather_ = false;
  return out;
}

void Mailbox::keep(ProtocolMessage m) {
  if (phase_of(m) >= kInitPhaseBase) return;  // a late copy of the initialisation stage's
  stash_[{phase_of(m), round_of(m)}][sender_of(m)] = std::move(m);
}

}  // namespace tessera::agent
