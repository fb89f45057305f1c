#pragma once
// The votes between the iterate and a fresh start of the kept set in the distributed GNC
// (GncAgentInput::kept_set_start with the chordal initialization): after GNC's rejected set,
// after each probe, where a capped pass changes nothing on a set not voted on before
// (GncDistributedOptions::stall_kept_set_start), and once before the final solve
// (GncDistributedOptions::final_kept_set_start). GncAgent runs their exchanges; this holds which
// vote runs and what the earlier ones summed, which tells when the vote before the final solve
// would keep the iterate (then it does not run). Every agent holds the same: the sums are the
// summed votes.

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace tessera {

class GncKeptStartVotes {
 public:
  explicit GncKeptStartVotes(bool enabled) : enabled_(enabled) {}

  /// Fresh starts of the kept set are voted on at all.
  bool enabled() const { return enabled_; }
  /// The vote before the final solve is due on the set `rejected` (ascending): `wanted` (a final
  /// solve follows and final_kept_set_start), not run yet, something rejected, and its outcome
  /// not known already.
  bool final_vote_due(bool wanted, const std::vector<std::uint64_t>& rejected) const {
    return wanted && enabled_ && !final_voted_ && !rejected.empty() && !settled(rejected);
  }
  void begin_final_vote() { final_voted_ = final_running_ = true; }
  /// A vote when the passes stall on the set `rejected` (ascending) is due: something rejected
  /// and no vote on this set before (its fresh start's cost is a function of the set).
  bool stall_vote_due(const std::vector<std::uint64_t>& rejected) const {
    if (!enabled_ || rejected.empty()) return false;
    for (const auto& entry : costs_)
      if (entry.first == rejected) return false;
    return true;
  }
  void begin_stall_vote() { stall_running_ = true; }
  /// Whether the vote that just ended was a stall vote (asked once, after ended()).
  bool take_stall_vote() {
    const bool stall = stall_running_;
    stall_running_ = false;
    return stall;
  }
  /// A vote on the set `rejected` ended, the fresh start's summed cost over the kept set
  /// `fresh_cost` (a function of the set): whether it was the vote before the final solve.
  bool ended(const std::vector<std::uint64_t>& rejected, double fresh_cost) {
    costs_.emplace_back(rejected, fresh_cost);
    const bool final_vote = final_running_;
    final_running_ = false;
    return final_vote;
  }
  /// The kept set's summed cost at the end of the last inlier pass when that pass was solved to
  /// the tolerance (the solve's last trace record, the same on every agent); NaN otherwise.
  void set_last_pass_cost(double cost) { last_pass_cost_ = cost; }

 private:
  bool settled(const std::vector<std::uint64_t>& rejected) const {
    // The fresh start of a set voted on before costs what that vote summed; an iterate solved to
    // the tolerance on the same set that ends clearly below it wins the vote (the margin covers
    // the two sums' different order of terms).
    if (!std::isfinite(last_pass_cost_)) return false;
    for (const auto& [set, cost] : costs_)
      if (set == rejected && last_pass_cost_ < cost - 1e-9 * std::abs(cost)) return true;
    return false;
  }

  bool enabled_;
  bool final_voted_ = false;    // the vote before the final solve ran (once)
  bool final_running_ = false;  // the running vote is that one
  bool stall_running_ = false;  // the running (or just ended) vote is a stall vote
  std::vector<std::pair<std::vector<std::uint64_t>, double>> costs_;  // every vote so far
  double last_pass_cost_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace tessera
