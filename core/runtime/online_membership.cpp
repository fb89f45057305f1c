#include "runtime/online_membership.hpp"

namespace tessera::runtime {

OnlineMembership::OnlineMembership(int robots) : robots_(static_cast<std::uint32_t>(robots)) {}

const std::set<std::uint32_t>& OnlineMembership::members(std::uint32_t epoch) const {
  return members_.at(epoch);
}

bool OnlineMembership::is_member(std::uint32_t agent, std::uint32_t epoch) const {
  return members(epoch).count(agent) > 0;
}

std::uint32_t OnlineMembership::lead_of(std::uint32_t epoch) const {
  auto it = members_.find(epoch);
  return it == members_.end() || it->second.empty() ? 0 : *it->second.begin();
}

bool OnlineMembership::absorbs(std::uint32_t robot, std::uint32_t epoch) const {
  return is_member(robot, epoch) || lost(robot);
}

Watermarks OnlineMembership::entering(const std::vector<Watermarks>& held,
                                      std::uint32_t epoch) const {
  AbsorbGate gate;
  Watermarks decision = gate.decide(held);
  for (auto& [robot, count] : decision)
    if (!absorbs(robot, epoch)) count = 0;
  return decision;
}

void OnlineMembership::heard_from(std::uint32_t agent) {
  if (agent < robots_ && !lost(agent)) heard_.insert(agent);
}

void OnlineMembership::admit(std::uint32_t epoch, const std::vector<std::uint32_t>& next) {
  members_[epoch + 1] = std::set<std::uint32_t>(next.begin(), next.end());
}

std::vector<std::uint32_t> OnlineMembership::next_members(
    std::uint32_t epoch, const std::vector<std::uint32_t>& lost_now) const {
  std::set<std::uint32_t> next = members(epoch);
  next.insert(heard_.begin(), heard_.end());
  for (std::uint32_t a : lost_now)
    if (!is_member(a, epoch)) next.erase(a);
  return {next.begin(), next.end()};
}

bool OnlineMembership::joiner_waiting(std::uint32_t epoch) const {
  for (std::uint32_t a : heard_)
    if (!is_member(a, epoch)) return true;
  return false;
}

void OnlineMembership::taken_over(const std::set<std::uint32_t>& lost,
                                  const std::set<std::uint32_t>& survivors,
                                  std::uint32_t next_epoch) {
  lost_.insert(lost.begin(), lost.end());
  for (std::uint32_t a : lost_) heard_.erase(a);
  floor_ = next_epoch;
  members_.erase(members_.begin(), members_.lower_bound(next_epoch));
  members_[next_epoch] = survivors;
}

}  // namespace tessera::runtime
