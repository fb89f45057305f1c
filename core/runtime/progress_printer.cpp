#include "runtime/progress_printer.hpp"

#include <cmath>
#include <cstdio>

namespace tessera::coordinator {

void ProgressPrinter::on_step(const CompletedStep& step, double ms) {
  if (!enabled_) return;
  const bool first = !last_ms_;
  if (first || step.phase == 5 || ms - *last_ms_ >= min_interval_ms_)
    print(step, ms);
  else
    pending_ = step;
}

void ProgressPrinter::finish() {
  if (pending_) print(*pending_, last_ms_.value_or(0));
}

void ProgressPrinter::on_stage(std::uint32_t stage, std::uint64_t iteration, double value) {
  if (!enabled_) return;
  finish();  // the rounds' last line first
  char buf[160];
  const auto low = static_cast<unsigned>(iteration & 0xffffffffu);
  if (stage == 1)
    std::snprintf(buf, sizeof(buf), "certificate: iteration %u, lambda_min estimate %.3e\n", low,
                  value);
  else if (stage == 3)
    std::snprintf(buf, sizeof(buf), "refinement: Newton step %u, CG iteration %u, gradient %.3e\n",
                  static_cast<unsigned>(iteration >> 32), low, value);
  else
    std::snprintf(buf, sizeof(buf),
                  "rounding: translation CG iteration %u, cost moved by the last steps %.3e\n", low,
                  value);
  out_ << buf << std::flush;
}

void ProgressPrinter::print(const CompletedStep& step, double ms) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "round %u%s: cost %.10g, grad norm %.3e\n", step.round,
                step.phase == 5 ? " (restart)" : "", step.cost, std::sqrt(step.grad_norm_sq));
  out_ << buf << std::flush;
  last_ms_ = ms;
  pending_.reset();
}

}  // namespace tessera::coordinator
