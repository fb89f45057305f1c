#include "runtime/stage_progress.hpp"

#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::agent {

void StageProgressOptions::validate() const {
  if (!(period_s > 0.0 && period_s <= 3600.0))
    throw InputError("StageProgressOptions::period_s must be in (0, 3600] seconds, got " +
                     std::to_string(period_s));
}

StageProgress::StageProgress(bool reporter, ProtocolChannel& channel, StageProgressOptions options)
    : reporter_(reporter),
      channel_(channel),
      period_(std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>((options.validate(), options.period_s)))) {}

void StageProgress::report(ProgressStage stage, std::uint64_t iteration, double value,
                           Clock::time_point now) {
  if (!reporter_) return;
  if (stage_ == stage && now - last_ < period_) return;
  stage_ = stage;
  last_ = now;
  ++sent_;
  channel_.report(StageProgressReport{stage, iteration, value});  // no agent waits for it
}

}  // namespace tessera::agent
