#include "transport/peer_gate.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <tessera/util/input_error.hpp>

#include "transport/fastdds/handshake_stall.hpp"
#include "transport/session.hpp"

namespace tessera::transport {

void PeerGateOptions::validate() const {
  if (!(timeout_s > 0)) throw InputError("peer gate: timeout_s must be positive");
  if (!(stall_after_s > 0)) throw InputError("peer gate: stall_after_s must be positive");
  if (max_reopens < 0) throw InputError("peer gate: max_reopens must not be negative");
  if (!(retire_notice_s >= 0)) throw InputError("peer gate: retire_notice_s must not be negative");
}

GateStep judge_peers(const SessionOptions& self, bool secured, const std::vector<PeerView>& peers,
                     double stall_after_s, bool joining) {
  // Several participants may carry one role's name (in a secured run anyone can advertise
  // it): an authenticated one stands for the role; else the most recently discovered one, so
  // a handshake counts as stalled only when no claimant of the role can still finish it.
  auto find = [&](bool coordinator, std::uint32_t id) -> const PeerView* {
    const PeerView* best = nullptr;
    for (const PeerView& v : peers) {
      if (v.who.coordinator != coordinator || (!coordinator && v.who.agent_id != id)) continue;
      if (v.authenticated) return &v;
      if (!best || v.known_for_s < best->known_for_s) best = &v;
    }
    return best;
  };
  const PeerView* coordinator = find(true, 0);
  if (!coordinator) return {GateStep::kWait, "the coordinator (not discovered yet)"};
  // Before the handshake check: a UDP-only re-creation starts every handshake afresh anyway.
  // Secured, the tag counts only from the authenticated coordinator (an unauthenticated
  // participant's name and tags are anyone's to claim).
  if (coordinator->tags.udp_only && self.uses_shared_memory() &&
      (!secured || coordinator->authenticated))
    return {GateStep::kReopenUdpOnly, "the coordinator talks UDP only"};
  if (!secured) return {GateStep::kPass, ""};
  std::vector<PeerIdentity> expected{PeerIdentity{self.run_id, true, 0}};
  for (std::uint32_t k = 0; k < self.num_agents; ++k)
    if (k != self.agent_id) expected.push_back(PeerIdentity{self.run_id, false, k});
  std::string missing;
  for (const PeerIdentity& want : expected) {
    const PeerView* v = find(want.coordinator, want.agent_id);
    std::string what;
    if (!v) {
      what = want.describe() + " (not discovered yet)";
    } else if (!v->authenticated) {
      if (cures_stalled_handshake(self.agent_id, want, v->known_for_s, stall_after_s, joining))
        return {GateStep::kReopenStalled, want.describe()};
      what = want.describe() + " (not authenticated yet)";
    }
    if (!what.empty()) missing += (missing.empty() ? "" : ", ") + what;
  }
  if (missing.empty()) return {GateStep::kPass, ""};
  return {GateStep::kWait, missing};
}

PeerGateResult pass_peer_gate(Session& s, const PeerGateOptions& o,
                              const std::function<void()>& on_poll) {
  o.validate();
  PeerGateResult r;
  const auto deadline = std::chrono::steady_clock::now() + Seconds(o.timeout_s);
  const bool secured = !s.options().security_dir.empty();
  // The forced re-creation (a test hook) judges any unfinished handshake stalled at once.
  bool force_pending = o.force_one_reopen && secured;
  for (;;) {
    if (on_poll) on_poll();
    // Counted before judging: any discovery, loss, handshake or match after this wakes the
    // wait below at once (only a stall, which is a duration, needs the poll).
    const std::uint64_t seen = s.mailroom().state_changes();
    const double stall_after_s = force_pending ? 0.0 : o.stall_after_s;
    const GateStep step =
        judge_peers(s.options(), secured, s.peer_views(), stall_after_s, o.joining);
    if (step.kind == GateStep::kPass) {
      r.status = WaitStatus::kReady;
      return r;
    }
    if (step.kind == GateStep::kReopenStalled && force_pending) {
      const std::string why = "DDS Security handshake with " + step.why +
                              " unfinished: re-creating this participant (forced once by a "
                              "test hook, not counted in the re-creations for real stalls)";
      r.events.push_back(why);
      s.replace_participant(s.options().shared_memory, Seconds(o.retire_notice_s), why);
      ++r.forced_reopens;
      force_pending = false;
      continue;
    }
    if (step.kind == GateStep::kReopenUdpOnly && r.udp_reopens == 0) {
      const std::string why =
          "the coordinator talks UDP only (its run survives a killed agent): re-creating this "
          "participant without shared memory";
      r.events.push_back(why);
      s.replace_participant(false, Seconds(o.retire_notice_s), why);
      ++r.udp_reopens;
      continue;
    }
    if (step.kind == GateStep::kReopenStalled && r.stall_reopens < o.max_reopens) {
      char buf[200];
      std::snprintf(buf, sizeof(buf),
                    "DDS Security handshake with %s unfinished after %g s (Fast DDS 2.9 "
                    "stall): re-creating this participant (%d of at most %d)",
                    step.why.c_str(), o.stall_after_s, r.stall_reopens + 1, o.max_reopens);
      r.events.push_back(buf);
      s.replace_participant(s.options().shared_memory, Seconds(o.retire_notice_s), buf);
      ++r.stall_reopens;
      continue;
    }
    r.missing = step.kind == GateStep::kReopenStalled
                    ? step.why + " (not authenticated; re-creations used up)"
                    : step.why;
    const Seconds left = deadline - std::chrono::steady_clock::now();
    if (left.count() <= 0) {
      r.status = WaitStatus::kTimeout;
      return r;
    }
    // Looks again on every change, and every 0.2 s or more often for a short stall bound (a
    // stall is a duration).
    const Seconds poll(std::clamp(stall_after_s / 2, 0.001, 0.2));
    Mailroom& room = s.mailroom();
    if (room.wait_for([&] { return room.state_changes_locked() != seen; }, std::min(left, poll)) ==
        WaitStatus::kStopped) {
      r.status = WaitStatus::kStopped;
      return r;
    }
  }
}

}  // namespace tessera::transport
