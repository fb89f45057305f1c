#pragma once
// When new stream data enters a distributed run. Each agent receives the batches of the
// stream on its own schedule (the transport delivers them at different times), but a new
// measurement between two blocks must change both agents' problems on the same round, or
// their views of the objective would differ. So data enters only at a round boundary, and
// only what EVERY agent holds: each agent reports in its round status how many batches of
// each robot it has absorbed (its watermarks); every agent receives all statuses, takes the
// element-wise minimum and lets exactly those batches in before the next round. Every agent
// computes the same minimum from the same statuses, so they agree without extra messages.

#include <cstdint>
#include <map>
#include <vector>

namespace tessera {

/// Batches absorbed per robot (robot -> count); absent robots count 0.
using Watermarks = std::map<std::uint32_t, std::uint64_t>;

class AbsorbGate {
 public:
  /// The watermarks every agent has reached (element-wise minimum of `reports`, one per
  /// agent, in any order), never below what entered before: this is what enters now. A robot
  /// missing from a report counts 0 for it.
  const Watermarks& decide(const std::vector<Watermarks>& reports);
  /// What entered so far.
  const Watermarks& entered() const { return entered_; }
  /// Batches of `robot` that entered so far.
  std::uint64_t entered(std::uint32_t robot) const;

 private:
  Watermarks entered_;
};

}  // namespace tessera
