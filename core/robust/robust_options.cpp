#include <cmath>
#include <cstdio>
#include <tessera/robust/robust_options.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {

std::string number_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

[[noreturn]] void bad_field(const char* field, const std::string& value, const char* rule) {
  throw InputError(std::string("RobustOptions.") + field + " = " + value + ": " + rule);
}

}  // namespace

const char* robust_kind_name(RobustKind kind) {
  if (kind == RobustKind::kPcmGnc) return "pcm-gnc";
  return kind == RobustKind::kGncTls ? "gnc-tls" : "none";
}

RobustKind parse_robust_kind(const std::string& name) {
  if (name == "none") return RobustKind::kNone;
  if (name == "gnc-tls") return RobustKind::kGncTls;
  if (name == "pcm-gnc") return RobustKind::kPcmGnc;
  throw InputError("unknown robust scheme '" + name + "' (valid: none, gnc-tls, pcm-gnc)");
}

const char* known_inliers_name(KnownInliers known) {
  return known == KnownInliers::kOdometry ? "odometry" : "none";
}

KnownInliers parse_known_inliers(const std::string& name) {
  if (name == "odometry") return KnownInliers::kOdometry;
  if (name == "none") return KnownInliers::kNone;
  throw InputError("unknown known-inlier set '" + name + "' (valid: odometry, none)");
}

const char* probe_cut_name(ProbeCut cut) {
  if (cut == ProbeCut::kAlways) return "always";
  return cut == ProbeCut::kAfterPasses ? "after-passes" : "auto";
}

ProbeCut parse_probe_cut(const std::string& name) {
  if (name == "always") return ProbeCut::kAlways;
  if (name == "after-passes") return ProbeCut::kAfterPasses;
  if (name == "auto") return ProbeCut::kAuto;
  throw InputError("'" + name + "' is not one of always, after-passes, auto");
}

const char* mu_step_hold_name(MuStepHold hold) {
  return hold == MuStepHold::kFalls ? "falls" : "crossings";
}

MuStepHold parse_mu_step_hold(const std::string& name) {
  if (name == "falls") return MuStepHold::kFalls;
  if (name == "crossings") return MuStepHold::kCrossings;
  throw InputError("'" + name + "' is not one of falls, crossings");
}

void RobustOptions::validate() const {
  if (!(std::isfinite(inlier_threshold) && inlier_threshold >= 0))
    bad_field("inlier_threshold", number_text(inlier_threshold),
              "must be >= 0 (0 = from the chi-square quantile)");
  if (!(inlier_quantile >= 0 && inlier_quantile < 1))
    bad_field("inlier_quantile", number_text(inlier_quantile),
              "must be in (0, 1), or 0 for 1 - 1e-4 / measurements");
  if (max_outer_iterations < 1)
    bad_field("max_outer_iterations", std::to_string(max_outer_iterations), "must be >= 1");
  if (inner_max_rounds < 0)
    bad_field("inner_max_rounds", std::to_string(inner_max_rounds), "must be >= 0 (0 = no cap)");
  if (inner_max_iterations < 0)
    bad_field("inner_max_iterations", std::to_string(inner_max_iterations),
              "must be >= 0 (0 = no cap)");
  if (!(std::isfinite(mu_step) && mu_step > 1))
    bad_field("mu_step", number_text(mu_step), "must be > 1");
  if (!(std::isfinite(mu_step_max) && (mu_step_max == 0 || mu_step_max >= mu_step)))
    bad_field("mu_step_max", number_text(mu_step_max), "must be 0 (off) or >= mu_step");
  if (!(std::isfinite(newton_mu_step_max) && (newton_mu_step_max == 0 || newton_mu_step_max > 1)))
    bad_field("newton_mu_step_max", number_text(newton_mu_step_max), "must be 0 (none) or > 1");
  if (mu_step_hold != MuStepHold::kCrossings && mu_step_hold != MuStepHold::kFalls)
    bad_field("mu_step_hold", std::to_string(static_cast<int>(mu_step_hold)),
              "must be crossings or falls");
  if (!(std::isfinite(jump_band) && (jump_band == 0 || jump_band > 1)))
    bad_field("jump_band", number_text(jump_band), "must be 0 (off) or > 1");
  if (!(std::isfinite(jump_band_max) && jump_band_max >= 0))
    bad_field("jump_band_max", number_text(jump_band_max),
              "must be >= 0 (<= jump_band: no widening)");
  if (recheck_max_rounds < 0)
    bad_field("recheck_max_rounds", std::to_string(recheck_max_rounds),
              "must be >= 0 (0 = no cap)");
  if (readmission_passes < 0)
    bad_field("readmission_passes", std::to_string(readmission_passes), "must be >= 0");
  if (recheck_probes < 0)
    bad_field("recheck_probes", std::to_string(recheck_probes), "must be >= 0 (0 = none)");
  if (!(std::isfinite(probe_ratio) && probe_ratio > 1))
    bad_field("probe_ratio", number_text(probe_ratio), "must be > 1");
  if (!(std::isfinite(probe_tail_ratio) && probe_tail_ratio >= 0))
    bad_field("probe_tail_ratio", number_text(probe_tail_ratio), "must be >= 0 (0 = always)");
  if (!(std::isfinite(probe_return_ratio) && probe_return_ratio >= 1))
    bad_field("probe_return_ratio", number_text(probe_return_ratio), "must be >= 1 (1 = none)");
  if (probe_cut != ProbeCut::kAlways && probe_cut != ProbeCut::kAfterPasses &&
      probe_cut != ProbeCut::kAuto)
    bad_field("probe_cut", std::to_string(static_cast<int>(probe_cut)),
              "must be always, after-passes or auto");
  if (swap_probes < 0)
    bad_field("swap_probes", std::to_string(swap_probes), "must be >= 0 (0 = none)");
  if (swap_near < 0) bad_field("swap_near", std::to_string(swap_near), "must be >= 0");
  if (!(std::isfinite(swap_kept_ratio) && swap_kept_ratio >= 0 && swap_kept_ratio <= 1))
    bad_field("swap_kept_ratio", number_text(swap_kept_ratio), "must be in [0, 1]");
  if (!(std::isfinite(swap_return_ratio) && swap_return_ratio >= 1))
    bad_field("swap_return_ratio", number_text(swap_return_ratio), "must be >= 1");
  if (gnc_refine_steps < 0)
    bad_field("gnc_refine_steps", std::to_string(gnc_refine_steps),
              "must be >= 0 (0 = weighted solves by rounds)");
  if (!(std::isfinite(newton_step_trust) && newton_step_trust >= 0 && newton_step_trust <= 1))
    bad_field("newton_step_trust", number_text(newton_step_trust), "must be in [0, 1] (0 = off)");
  if (!(std::isfinite(weight_tolerance) && weight_tolerance >= 0))
    bad_field("weight_tolerance", number_text(weight_tolerance), "must be >= 0");
}

}  // namespace tessera
