#include "runtime/stage_progress.hpp"

#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::agent {

void StageProgressOptions::validate() const {
  if (!(period_s > 0.0 && period_s <= 3600.0))
    throw InputError("StageProgressOptions::period_s must be in (0, 3600] seconds, got " +
                     std::to_string(period_s));
}

RoundStatusMessage stage_progress_status(std::uint32_t sequence, ProgressStage stage,
                                         std::uint64_t iteration, double value) {
  RoundStatusMessage m;
  m.round = sequence;
  m.grad_norm_sq = static_cast<double>(iteration);
  m.phase = kStageProgressPhase;
  m.sender = 0;
  m.cost = value;
  m.block_grad_norm = static_cast<double>(stage);
  return m;
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
  // To the coordinator (its reports' topic) only: no agent waits for it.
  channel_.send(
      OutgoingMessage{stage_progress_status(sent_++, stage, iteration, value), false, {}});
}

}  // namespace tessera::agent
