#pragma once
// Agent 0's progress reports during the stages after the rounds: the certificate's LOBPCG
// iterations, the Newton refinement's CG iterations and the rounding's translation CG iterations.
// Each is one all-agent step, and at a million poses there are hundreds of them taking many
// minutes; without these reports the coordinator's output showed only that the agents were alive. A
// report is a StageProgressReport (agent_report.hpp, read by the coordinator as agent 0's other
// reports), sent when the stage begins and then at most once per period, so its traffic does not
// depend on how fast the iterations go.

#include <chrono>
#include <cstdint>
#include <optional>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

/// The refinement's iteration field: its trust-region step (1-based) in the high 32 bits and the
/// CG iteration within that step in the low ones. Both fit in the report's one iteration field
/// (StageProgressReport::iteration), so the refinement's reports are the same size as the others'.
constexpr std::uint64_t refinement_iteration(std::uint32_t newton_step,
                                             std::uint32_t cg_iteration) {
  return (static_cast<std::uint64_t>(newton_step) << 32) | cg_iteration;
}

struct StageProgressOptions {
  /// Seconds between two reports of one stage, (0, 3600]: the coordinator prints each as a
  /// line, so this is launch's line rate during the certificate and the rounding.
  double period_s = 2.0;

  /// Throws InputError naming the field when it is out of range.
  void validate() const;
};

/// One per agent run (the Mailbox holds it).
class StageProgress {
 public:
  using Clock = std::chrono::steady_clock;

  /// `reporter`: this agent sends the reports (agent 0); the others' calls do nothing.
  /// `channel` must outlive this object. Throws InputError when `options` are invalid.
  StageProgress(bool reporter, ProtocolChannel& channel, StageProgressOptions options = {});

  /// Sends a report when this is the reporter and the stage is new or a period has passed
  /// since the last report.
  void report(ProgressStage stage, std::uint64_t iteration, double value,
              Clock::time_point now = Clock::now());

  std::uint32_t sent() const { return sent_; }

 private:
  bool reporter_;
  ProtocolChannel& channel_;
  Clock::duration period_;
  std::optional<ProgressStage> stage_;
  Clock::time_point last_{};
  std::uint32_t sent_ = 0;
};

}  // namespace tessera::agent
