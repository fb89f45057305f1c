#include "transport/peer_tracking.hpp"

#include <cstdio>
#include <optional>
#include <sstream>

#include "transport/fastdds/shm_receive_watch.hpp"

namespace tessera::transport {

PeerTracker::PeerTracker(Mailroom& room, const SessionOptions& options, PeerIdentity me)
    : room_(room),
      opt_(options),
      me_(std::move(me)),
      tolerate_agent_loss_(options.tolerate_agent_loss),
      secured_(!options.security_dir.empty()) {}

std::string prefix_text(const GuidPrefix& prefix) {
  std::ostringstream os;
  os << prefix;
  return os.str();
}

void PeerTracker::add_own_prefix(const GuidPrefix& prefix) {
  std::lock_guard<std::mutex> lock(own_mutex_);
  own_prefixes_.insert(prefix);
}

bool PeerTracker::is_own(const GuidPrefix& prefix) const {
  std::lock_guard<std::mutex> lock(own_mutex_);
  return own_prefixes_.count(prefix) > 0;
}

void PeerTracker::discovered(const GuidPrefix& prefix, const PeerIdentity& who,
                             const ParticipantTags& tags) {
  const Clock::time_point now = Clock::now();
  if (secured_) {
    // The name and tags are plaintext SPDP data that anyone can send: they count only from a
    // participant whose handshake completed (authenticated() admits it).
    const bool admitted = room_.with_lock([&] {
      if (admitted_.count(prefix)) return true;
      auto it = candidates_.find(prefix);
      if (it == candidates_.end())
        candidates_.emplace(prefix, Candidate{who, tags, now});
      else {
        it->second.who = who;
        it->second.tags = tags;
      }
      return false;
    });
    if (!admitted) {
      if (opt_.verbose)
        std::fprintf(stderr, "%s: discovered a participant named %s (counted once authenticated)\n",
                     participant_name(me_).c_str(), who.describe().c_str());
      room_.notify_state_changed();
      return;
    }
  }
  admit(prefix, who, tags, now);
}

void PeerTracker::admit(const GuidPrefix& prefix, const PeerIdentity& who,
                        const ParticipantTags& tags, Clock::time_point discovered_at) {
  std::string clash, forgotten;
  room_.with_lock([&] {
    if (replaced_.count(prefix_text(prefix))) return 0;  // a replaced participant seen late
    // Forget the participants this one replaces (same role only: a tag cannot make another
    // process's participant disappear), whether or not they were discovered here yet.
    for (const std::string& old : tags.replaces) {
      replaced_.insert(old);
      for (auto it = peers_.begin(); it != peers_.end(); ++it)
        if (it->first != prefix && prefix_text(it->first) == old &&
            it->second.coordinator == who.coordinator && it->second.agent_id == who.agent_id) {
          forgotten = left_reason(it->second);
          lost_.erase(it->first);
          authenticated_.erase(it->first);
          discovered_at_.erase(it->first);
          tags_.erase(it->first);
          peers_.erase(it);
          break;
        }
    }
    for (const auto& [p, id] : peers_)
      if (p != prefix && !lost_.count(p) && id.coordinator == who.coordinator &&
          id.agent_id == who.agent_id)
        clash = who.describe();
    if (!who.coordinator && who.agent_id == me_.agent_id && !me_.coordinator)
      clash = who.describe();
    if (who.coordinator && me_.coordinator) clash = who.describe();
    peers_[prefix] = who;
    discovered_at_.emplace(prefix, discovered_at);
    tags_[prefix] = tags;
    return 0;
  });
  if (opt_.verbose)
    std::fprintf(stderr, "%s: discovered %s%s\n", participant_name(me_).c_str(),
                 who.describe().c_str(),
                 tags.replaces.empty() ? "" : " (a new participant of that process)");
  // Its old participant may have left already (it is deleted once the new one is known).
  if (!forgotten.empty()) room_.cancel_pending_stop(forgotten);
  room_.notify_state_changed();
  if (!clash.empty())
    room_.request_stop(2, "two processes claim to be " + clash + " of run '" + opt_.run_id +
                              "' (check --id / --run-id)");
}

void PeerTracker::changed(const GuidPrefix& prefix, const ParticipantTags& tags) {
  std::string forgotten;
  room_.with_lock([&] {
    if (secured_ && !admitted_.count(prefix)) {  // a candidate's tags decide nothing yet
      auto it = candidates_.find(prefix);
      if (it != candidates_.end()) {
        // Retiring speaks only for itself: the gate stops waiting for this participant.
        if (tags.retiring)
          candidates_.erase(it);
        else
          it->second.tags = tags;
      }
      return 0;
    }
    if (!tags.retiring) return 0;
    replaced_.insert(prefix_text(prefix));
    auto it = peers_.find(prefix);
    if (it == peers_.end()) return 0;
    forgotten = left_reason(it->second);
    lost_.erase(prefix);
    authenticated_.erase(prefix);
    discovered_at_.erase(prefix);
    tags_.erase(prefix);
    peers_.erase(it);
    return 0;
  });
  if (!forgotten.empty()) room_.cancel_pending_stop(forgotten);
  room_.notify_state_changed();
}

void PeerTracker::authenticated(const GuidPrefix& prefix) {
  std::optional<Candidate> candidate;
  room_.with_lock([&] {
    authenticated_.insert(prefix);
    if (!admitted_.insert(prefix).second) return 0;
    auto it = candidates_.find(prefix);
    if (it != candidates_.end()) {
      candidate = it->second;
      candidates_.erase(it);
    }
    return 0;
  });
  if (candidate)
    admit(prefix, candidate->who, candidate->tags, candidate->discovered_at);
  else
    room_.notify_state_changed();
}

void PeerTracker::restart_handshakes() {
  room_.with_lock([&] {
    authenticated_.clear();
    const auto now = Clock::now();
    for (auto& [p, at] : discovered_at_) at = now;
    for (auto& [p, c] : candidates_) c.discovered_at = now;
    return 0;
  });
}

namespace {
// A peer that "stopped responding" may be alive while this process's own shared-memory listener
// is stuck (transport/fastdds/shm_receive_watch.hpp): the loss then names that too.
std::string with_stuck_listener_note() {
  const std::string stuck = shm_receive_note();
  return stuck.empty() ? std::string() : " (" + stuck + ")";
}
}  // namespace

std::string PeerTracker::left_reason(const PeerIdentity& who) const {
  return "lost " + who.describe() + " of run '" + opt_.run_id + "': it left the run";
}

void PeerTracker::left(const GuidPrefix& prefix) {
  gone(prefix, "left the run", /*graceful=*/true);
}

void PeerTracker::dropped(const GuidPrefix& prefix) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "stopped responding (participant lease of %.1f s expired)",
                opt_.lease_s);
  gone(prefix, buf, /*graceful=*/false);
}

void PeerTracker::liveliness_lost(const GuidPrefix& prefix) {
  std::optional<PeerIdentity> who;
  bool fatal = false;
  room_.with_lock([&] {
    auto it = peers_.find(prefix);
    if (it != peers_.end() && !lost_.count(prefix)) {
      who = it->second;
      fatal = loss_fatal_ && !(tolerate_agent_loss_ && !it->second.coordinator);
    }
    return 0;
  });
  if (!who) return;
  char buf[96];
  std::snprintf(buf, sizeof(buf), "stopped responding (writer liveliness of %.1f s lost)",
                opt_.lease_s);
  if (opt_.verbose)
    std::fprintf(stderr, "%s: %s: %s\n", participant_name(me_).c_str(), who->describe().c_str(),
                 buf);
  if (fatal)
    room_.request_stop_after(1,
                             "lost " + who->describe() + " of run '" + opt_.run_id + "': it " +
                                 buf + with_stuck_listener_note(),
                             Seconds(kLivelinessStopDelayS));
}

void PeerTracker::gone(const GuidPrefix& prefix, const std::string& how, bool graceful) {
  std::optional<PeerIdentity> who;
  bool fatal = false;
  room_.with_lock([&] {
    candidates_.erase(prefix);  // never authenticated: its leaving means nothing
    if (replaced_.count(prefix_text(prefix))) return 0;  // forgotten: its successor is live
    auto it = peers_.find(prefix);
    if (it != peers_.end() && !lost_.count(prefix)) {
      lost_.insert(prefix);
      who = it->second;
      fatal = loss_fatal_ && !(tolerate_agent_loss_ && !it->second.coordinator);
    }
    return 0;
  });
  if (!who) return;
  if (opt_.verbose)
    std::fprintf(stderr, "%s: lost %s: %s\n", participant_name(me_).c_str(),
                 who->describe().c_str(), how.c_str());
  room_.notify_state_changed();
  if (!fatal) return;
  const std::string why = graceful ? left_reason(*who)
                                   : "lost " + who->describe() + " of run '" + opt_.run_id +
                                         "': it " + how + with_stuck_listener_note();
  // A peer that left cleanly has (almost always) sent or seen an ABORT that says why;
  // give it a moment to arrive so the message names the cause, not the symptom.
  if (graceful)
    room_.request_stop_after(1, why, Seconds(2.0));
  else
    room_.request_stop(1, why);
}

void PeerTracker::set_loss_fatal(bool fatal) {
  room_.with_lock([&] { return loss_fatal_ = fatal; });
}

void PeerTracker::set_agent_loss_tolerated(bool tolerated) {
  room_.with_lock([&] { return tolerate_agent_loss_ = tolerated; });
}

std::vector<PeerIdentity> PeerTracker::live_peers() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  std::vector<PeerIdentity> out;
  for (const auto& [p, who] : peers_)
    if (!lost_.count(p)) out.push_back(who);
  return out;
}

std::vector<PeerView> PeerTracker::peer_views(bool secured) const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  const auto now = std::chrono::steady_clock::now();
  std::vector<PeerView> out;
  for (const auto& [p, who] : peers_) {
    if (lost_.count(p)) continue;
    PeerView v;
    v.who = who;
    auto at = discovered_at_.find(p);
    if (at != discovered_at_.end())
      v.known_for_s = std::chrono::duration<double>(now - at->second).count();
    v.authenticated = !secured || authenticated_.count(p) > 0;
    auto t = tags_.find(p);
    if (t != tags_.end()) v.tags = t->second;
    out.push_back(v);
  }
  for (const auto& [p, c] : candidates_) {
    PeerView v;
    v.who = c.who;
    v.known_for_s = std::chrono::duration<double>(now - c.discovered_at).count();
    v.authenticated = false;
    v.tags = c.tags;
    out.push_back(v);
  }
  return out;
}

std::size_t PeerTracker::peers_ever_seen() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  return peers_.size();
}

std::vector<std::uint32_t> PeerTracker::lost_agents() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  std::set<std::uint32_t> lost, live;
  for (const auto& [p, who] : peers_) {
    if (who.coordinator) continue;
    (lost_.count(p) ? lost : live).insert(who.agent_id);
  }
  std::vector<std::uint32_t> out;
  for (auto k : lost)
    if (!live.count(k)) out.push_back(k);
  return out;
}

const PeerIdentity* PeerTracker::known_locked(const GuidPrefix& prefix) const {
  auto it = peers_.find(prefix);
  return it == peers_.end() ? nullptr : &it->second;
}

const PeerIdentity* PeerTracker::live_locked(const GuidPrefix& prefix) const {
  return lost_.count(prefix) ? nullptr : known_locked(prefix);
}

std::string PeerTracker::describe_locked(const GuidPrefix& prefix) const {
  auto it = peers_.find(prefix);
  if (it != peers_.end()) return it->second.describe() + (lost_.count(prefix) ? " (lost)" : "");
  std::ostringstream os;
  os << "unknown " << prefix;
  return os.str();
}

}  // namespace tessera::transport
