#pragma once
// The coordinator's progress lines ("round K: cost C, grad norm G", "round K (restart): ...";
// public output, which tessera launch passes on), at most one per `min_interval_ms` (one a
// round would be 1456 lines for kitti_02, each one a pipe write and ~3 wake-ups on a busy
// host). Always printed: the first completed step, every restart and, through
// finish(), the last step seen; in between, the newest step once the interval has passed.

#include <cstdint>
#include <optional>
#include <ostream>

namespace tessera::coordinator {

/// One completed status step of the solve: a round (phase 1) or a restart (phase 5), with the
/// sums over every agent.
struct CompletedStep {
  std::uint32_t round = 0, phase = 1;
  double cost = 0, grad_norm_sq = 0;
};

class ProgressPrinter {
 public:
  /// `enabled`: print at all (--progress); `min_interval_ms` >= 0 (0: every step).
  ProgressPrinter(bool enabled, std::ostream& out, double min_interval_ms = 100.0)
      : enabled_(enabled), out_(out), min_interval_ms_(min_interval_ms) {}

  /// A step completed `ms` after the rounds started (steps in protocol order).
  void on_step(const CompletedStep& step, double ms);
  /// Prints the newest step if it was held back (the run's last line of progress).
  void finish();
  /// Agent 0's progress report of a stage after the rounds (runtime/stage_progress.hpp; it
  /// sends a few a minute): stage 1 "certificate: iteration K, lambda_min estimate V",
  /// stage 2 "rounding: translation CG iteration K, cost still moving V", stage 3
  /// "refinement: Newton step S, CG iteration K, gradient G" (`iteration` packs S and K:
  /// refinement_iteration()); printed at once.
  void on_stage(std::uint32_t stage, std::uint64_t iteration, double value);

 private:
  void print(const CompletedStep& step, double ms);
  bool enabled_;
  std::ostream& out_;
  double min_interval_ms_;
  std::optional<double> last_ms_;         // when the last line was printed
  std::optional<CompletedStep> pending_;  // newest step not printed yet
};

}  // namespace tessera::coordinator
