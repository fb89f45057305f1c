#pragma once
// The votes between the iterate and a fresh start of the kept set in the distributed GNC
// (GncAgentInput::kept_set_start with the chordal initialization): after GNC's rejected set,
// after each probe, where a capped pass changes nothing on a set not voted on before
// (GncDistributedOptions::stall_kept_set_start), and once before the final solve
// (GncDistributedOptions::final_kept_set_start). GncAgent runs their exchanges; this holds which
// vote runs and what the earlier ones summed, which tells when the vote before the final solve
// would keep the iterate (then it does not run). Every agent holds the same: the sums are the
// summed votes.

#include <algorithm>
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
  /// Which vote runs: after GNC or a probe (kStart), where the passes stall
  /// (GncDistributedOptions::stall_kept_set_start) or before the final solve.
  enum class Kind { kStart, kStall, kFinal };

  /// The vote before the final solve is due on the set `rejected` (ascending): `wanted` (a final
  /// solve follows and final_kept_set_start), not run yet, something rejected, and its outcome
  /// not known already.
  bool final_vote_due(bool wanted, const std::vector<std::uint64_t>& rejected) const {
    return wanted && enabled_ && !final_voted_ && !rejected.empty() && !settled(rejected);
  }
  /// A vote where the passes stall on the set `rejected` (ascending) is due: something rejected
  /// and no vote on this set before (its fresh start's cost is a function of the set).
  bool stall_vote_due(const std::vector<std::uint64_t>& rejected) const {
    return enabled_ && !rejected.empty() && !voted_on(rejected);
  }
  /// The next vote is of `kind` (kStart unless said otherwise).
  void begin(Kind kind) {
    running_ = kind;
    if (kind == Kind::kFinal) final_voted_ = true;
  }
  /// A vote on the set `rejected` ended, the fresh start's summed cost over the kept set
  /// `fresh_cost` (a function of the set): which vote it was.
  Kind ended(const std::vector<std::uint64_t>& rejected, double fresh_cost) {
    costs_.emplace_back(rejected, fresh_cost);
    const Kind kind = running_;
    running_ = Kind::kStart;
    return kind;
  }
  /// The kept set's summed cost at the end of the last inlier pass when that pass was solved to
  /// the tolerance (the solve's last trace record, the same on every agent); NaN otherwise.
  void set_last_pass_cost(double cost) { last_pass_cost_ = cost; }

 private:
  bool voted_on(const std::vector<std::uint64_t>& rejected) const {
    return std::any_of(costs_.begin(), costs_.end(),
                       [&](const auto& entry) { return entry.first == rejected; });
  }
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
  bool final_voted_ = false;     // the vote before the final solve ran (once)
  Kind running_ = Kind::kStart;  // the running vote
  std::vector<std::pair<std::vector<std::uint64_t>, double>> costs_;  // every vote so far
  double last_pass_cost_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace tessera
