#include "transport/readiness.hpp"

#include <algorithm>
#include <chrono>

namespace tessera::transport {

Readiness::Readiness(Mailroom& room, const SessionOptions& options, PeerIdentity me,
                     const PeerTracker& peers, const DdsTrace& trace)
    : room_(room), opt_(options), me_(std::move(me)), peers_(peers), trace_(trace) {}

void Readiness::expect(const std::string& endpoint, Expect e, std::uint32_t agent) {
  if (e != Expect::kNone) expect_[endpoint] = {e, agent};
}

void Readiness::on_matched(const std::string& endpoint, const GuidPrefix& prefix, int change) {
  if (peers_.is_own(prefix)) return;
  room_.with_lock([&] {
    auto& set = matched_[endpoint];
    if (change > 0) {
      set.insert(prefix);
    } else if (change < 0) {
      auto it = set.find(prefix);
      if (it != set.end()) set.erase(it);
    }
    trace_("%s %s %s (change %+d, now %zu)", endpoint.c_str(),
           change > 0   ? "matched"
           : change < 0 ? "unmatched"
                        : "match event without change from",
           peers_.describe_locked(prefix).c_str(), change, set.size());
    return 0;
  });
  room_.notify_state_changed();
}

void Readiness::on_ready(const PeerIdentity& from) {
  room_.with_lock([&] { return ready_from_.insert(from.describe()).second; });
  trace_("READY from %s", from.describe().c_str());
  room_.notify_state_changed();
}

void Readiness::on_finished() {
  room_.with_lock([&] { return finished_ = true; });
  room_.notify_state_changed();
}

void Readiness::on_abort(const PeerIdentity& from) {
  if (!from.coordinator) return;
  room_.with_lock([&] { return coordinator_aborted_ = true; });
  room_.notify_state_changed();
}

void Readiness::forget_matches() {
  room_.with_lock([&] {
    matched_.clear();
    return 0;
  });
}

bool Readiness::has_matched_locked(const std::string& endpoint, const PeerIdentity& who) const {
  auto it = matched_.find(endpoint);
  if (it == matched_.end()) return false;
  for (const GuidPrefix& p : it->second)
    if (const PeerIdentity* peer = peers_.live_locked(p))
      if (peer->describe() == who.describe()) return true;
  return false;
}

std::vector<PeerIdentity> Readiness::expected_peers(Expect e, std::uint32_t one) const {
  std::vector<PeerIdentity> out;
  if (!opt_.expect_coordinator) {
    if (e == Expect::kCoordinator) e = Expect::kNone;
    if (e == Expect::kOtherAgentsAndCoordinator) e = Expect::kOtherAgents;
  }
  auto agent = [&](std::uint32_t k) { return PeerIdentity{opt_.run_id, false, k}; };
  switch (e) {
    case Expect::kNone:
      break;
    case Expect::kCoordinator:
      out.push_back(PeerIdentity{opt_.run_id, true, 0});
      break;
    case Expect::kOtherAgentsAndCoordinator:
      out.push_back(PeerIdentity{opt_.run_id, true, 0});
      [[fallthrough]];
    case Expect::kOtherAgents:
      for (std::uint32_t k = 0; k < opt_.num_agents; ++k)
        if (me_.coordinator || k != me_.agent_id) out.push_back(agent(k));
      break;
    case Expect::kAllAgents:
      for (std::uint32_t k = 0; k < opt_.num_agents; ++k) out.push_back(agent(k));
      break;
    case Expect::kAgent:
      out.push_back(agent(one));
      break;
  }
  return out;
}

std::vector<PeerIdentity> Readiness::other_processes() const {
  std::vector<PeerIdentity> others = expected_peers(Expect::kOtherAgents);
  if (!me_.coordinator && opt_.expect_coordinator)
    others.push_back(PeerIdentity{opt_.run_id, true, 0});
  return others;
}

bool Readiness::endpoints_matched(std::string* missing) const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  return endpoints_matched_locked(missing);
}

bool Readiness::endpoints_matched_locked(std::string* missing) const {
  std::set<std::string> absent;
  for (const auto& [endpoint, e] : expect_) {
    std::set<std::string> have;
    auto it = matched_.find(endpoint);
    if (it != matched_.end())
      for (const GuidPrefix& p : it->second)
        if (const PeerIdentity* peer = peers_.live_locked(p)) have.insert(peer->describe());
    for (const auto& want : expected_peers(e.first, e.second))
      if (!have.count(want.describe())) absent.insert(want.describe());
  }
  if (missing) {
    missing->clear();
    for (const auto& a : absent) *missing += (missing->empty() ? "" : ", ") + a;
  }
  return absent.empty();
}

std::string Readiness::describe_matched_locked(const std::string& endpoint) const {
  std::string who;
  auto it = matched_.find(endpoint);
  if (it != matched_.end())
    for (const auto& p : it->second) who += " " + peers_.describe_locked(p);
  return who;
}

bool Readiness::finished() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  return finished_.load();
}

WaitStatus Readiness::wait_finished(Seconds timeout) {
  return room_.wait_for([&] { return finished_.load(); }, timeout);
}

std::string Readiness::describe_not_ready_locked(const PeerIdentity& who,
                                                 const std::string& ready_reader) const {
  bool seen = false, live = false;
  for (const auto& [p, id] : peers_.all_locked())
    if (id.describe() == who.describe()) {
      seen = true;
      live = live || !peers_.lost_locked(p);
    }
  if (!live) return who.describe() + (seen ? " (lost)" : " (not discovered)");
  if (!has_matched_locked(ready_reader, who))
    return who.describe() + " (discovered, its writer not matched by " + ready_reader + ")";
  return who.describe() + " (its writer matched, nothing received)";
}

WaitStatus Readiness::barrier(Seconds timeout, std::string* missing,
                              const std::function<void()>& send_ready,
                              const std::function<void()>& dump_match_state,
                              const std::string& ready_reader) {
  const auto start = std::chrono::steady_clock::now();
  std::string absent;
  trace_("barrier: waiting for endpoints to match");
  WaitStatus st = room_.wait_for([&] { return endpoints_matched_locked(&absent); }, timeout);
  if (st != WaitStatus::kReady) {
    if (missing) *missing = "endpoints not matched with " + absent;
    trace_("barrier: endpoints not matched with %s", absent.c_str());
    dump_match_state();
    return st;
  }
  trace_("barrier: endpoints matched, sending READY");
  send_ready();
  const std::vector<PeerIdentity> others = other_processes();
  const Seconds left = timeout - (std::chrono::steady_clock::now() - start);
  st = room_.wait_for(
      [&] {
        absent.clear();
        for (const auto& p : others)
          if (!ready_from_.count(p.describe()))
            absent += (absent.empty() ? "" : ", ") + p.describe();
        return absent.empty();
      },
      left);
  if (st == WaitStatus::kTimeout) {
    // Who, and what this process knows of them: undiscovered, READY's endpoints unmatched, or
    // matched with nothing received (the peer never sent READY or its samples were lost).
    absent = room_.with_lock([&] {
      std::string why;
      for (const auto& p : others)
        if (!ready_from_.count(p.describe()))
          why += (why.empty() ? "" : ", ") + describe_not_ready_locked(p, ready_reader);
      return why;
    });
    if (missing) *missing = "no READY from " + absent;
    trace_("barrier: no READY from %s", absent.c_str());
    dump_match_state();
  } else if (st == WaitStatus::kReady) {
    trace_("barrier: passed");
  }
  return st;
}

void Readiness::wait_matched_or_gone(const std::string& endpoint, Seconds timeout,
                                     Seconds unseen_patience) {
  const std::vector<PeerIdentity> others = other_processes();
  // Every expected peer has matched `endpoint` or is gone; with `include_unseen` false,
  // peers never discovered are not waited for.
  auto reached = [&](bool include_unseen) {
    std::set<std::string> have, seen;
    auto it = matched_.find(endpoint);
    if (it != matched_.end())
      for (const GuidPrefix& p : it->second)
        if (const PeerIdentity* peer = peers_.known_locked(p)) have.insert(peer->describe());
    for (const auto& [p, who] : peers_.all_locked()) {
      seen.insert(who.describe());
      if (peers_.lost_locked(p))
        have.insert(who.describe());  // no point waiting for a peer that is gone
    }
    for (const auto& p : others)
      if (!have.count(p.describe()) && (include_unseen || seen.count(p.describe()))) return false;
    return true;
  };
  // A peer never seen may still be starting: wait for it, but only `unseen_patience`.
  const Seconds first = std::min(timeout, unseen_patience);
  if (room_.wait_for([&] { return reached(true); }, first, /*interruptible=*/false) !=
      WaitStatus::kReady)
    room_.wait_for([&] { return reached(false); }, timeout - first, /*interruptible=*/false);
}

bool Readiness::wait_coordinator_acknowledged(Seconds timeout) {
  if (me_.coordinator || !opt_.expect_coordinator) return true;
  auto acknowledged_or_gone = [&] {
    if (coordinator_aborted_) return true;
    for (const auto& [p, who] : peers_.all_locked())
      if (who.coordinator && peers_.lost_locked(p)) return true;
    return false;
  };
  const bool done =
      room_.wait_for(acknowledged_or_gone, timeout, /*interruptible=*/false) == WaitStatus::kReady;
  trace_("linger: the coordinator %s",
         done ? "acknowledged the abort (or is gone)" : "did not acknowledge the abort in time");
  return done;
}

}  // namespace tessera::transport
