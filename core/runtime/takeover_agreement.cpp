#include "runtime/takeover_agreement.hpp"

#include <algorithm>
#include <utility>

namespace tessera::runtime {

TakeoverAgreement::TakeoverAgreement(std::set<std::uint32_t> members, std::uint32_t me)
    : members_(std::move(members)), me_(me) {}

bool TakeoverAgreement::suspect(const std::set<std::uint32_t>& lost) {
  bool grew = false;
  for (std::uint32_t a : lost)
    if (members_.count(a) > 0) grew = lost_.insert(a).second || grew;
  return grew;
}

bool TakeoverAgreement::vote(const TakeoverVote& v) {
  if (members_.count(v.sender) == 0) return false;
  votes_[v.sender] = v;
  return suspect(v.lost);
}

std::set<std::uint32_t> TakeoverAgreement::survivors() const {
  std::set<std::uint32_t> out;
  for (std::uint32_t a : members_)
    if (lost_.count(a) == 0) out.insert(a);
  return out;
}

bool TakeoverAgreement::complete() const {
  if (lost_.empty()) return false;
  for (std::uint32_t s : survivors()) {
    auto it = votes_.find(s);
    if (it == votes_.end() || it->second.lost != lost_) return false;
  }
  return true;
}

std::uint32_t TakeoverAgreement::next_epoch() const {
  std::uint32_t newest = 0;
  for (std::uint32_t s : survivors()) newest = std::max(newest, votes_.at(s).at_epoch);
  return newest + 1;
}

Watermarks TakeoverAgreement::entered() const {
  Watermarks out;
  for (std::uint32_t s : survivors())
    for (const auto& [robot, count] : votes_.at(s).entered)
      out[robot] = std::max(out[robot], count);
  return out;
}

}  // namespace tessera::runtime
