#include "launch/forwarded_flags.hpp"

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <string>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/robust/robust_options.hpp>
#include <tessera/util/input_error.hpp>

#include "cli/run_wide_args.hpp"

namespace tessera::launch {

namespace {

// `value` as a number, else an InputError naming the flag.
double number(const std::string& value, const char* flag) {
  errno = 0;
  char* end = nullptr;
  const double x = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || errno != 0)
    throw InputError(std::string("option --") + flag + ": '" + value + "' is not a number");
  return x;
}

// A number in [lo, hi], else an InputError naming the flag.
double number_in(const std::string& value, const char* flag, double lo, double hi,
                 const char* range) {
  const double x = number(value, flag);
  if (!(x >= lo && x <= hi))
    throw InputError(std::string("launch: --") + flag + " must be in " + range + " seconds");
  return x;
}

void check_status_interval(const std::string& v) {
  number_in(v, "status-interval", 0, 86400, "0..86400");
}

void check_progress_interval(const std::string& v) {
  number_in(v, "progress-interval", 0, 3600, "0..3600");
}

void check_partition_time(const std::string& v) {
  number_in(v, "partition-time", 0, 86400, "0..86400");
}

void check_partition_nice(const std::string& v) {
  const double x = number(v, "partition-nice");
  if (!(x >= -20 && x <= 0) || x != static_cast<double>(static_cast<int>(x)))
    throw InputError("launch: --partition-nice must be a whole number in -20..0");
}

void check_refine(const std::string& v) {
  NewtonRefineOptions checked;
  set_refine_mode(checked, v);
}

// A tolerance >= 0 (0 = the solver's default), else an InputError naming the flag.
void check_tolerance(const std::string& v, const char* flag) {
  if (!(number(v, flag) >= 0))
    throw InputError(std::string("option --") + flag + ": '" + v + "' is not a number >= 0");
}
void check_refine_grad_tol(const std::string& v) {
  check_tolerance(v, "refine-grad-tol");
}
void check_refine_rel_tol(const std::string& v) {
  check_tolerance(v, "refine-rel-tol");
}
void check_refine_sigma(const std::string& v) {
  NewtonRefineOptions check;
  set_sigma_mode(check, v);
}

// `v` as a whole number, else an InputError naming the flag.
long whole_number(const std::string& v, const char* flag) {
  errno = 0;
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno != 0)
    throw InputError(std::string("option --") + flag + ": '" + v + "' is not a whole number");
  return x;
}

// A whole number in [lo, hi], else an InputError naming the flag.
void whole_number_in(const std::string& v, const char* flag, long lo, long hi) {
  const long x = whole_number(v, flag);
  if (x < lo || x > hi)
    throw InputError(std::string("option --") + flag + ": '" + v + "' is not a whole number in " +
                     std::to_string(lo) + ".." + std::to_string(hi));
}
void check_reference_cost(const std::string& v) {
  const double f = number(v, "reference-cost");
  if (!(f > 0 && std::isfinite(f)))
    throw InputError("option --reference-cost: '" + v +
                     "' is not a finite number > 0 (the optimal cost f*)");
}
void check_setup_at_once(const std::string& v) {
  whole_number_in(v, "setup-at-once", 0, 1000);
}
void check_coarse_every(const std::string& v) {
  whole_number_in(v, "coarse-every", 0, 1000000);
}
// The coarse space's names and ranges are the core's (parse_coarse_space, CoarseOptions).
void check_coarse_space(const std::string& v) {
  try {
    parse_coarse_space(v);
  } catch (const InputError& e) {
    throw InputError(std::string("option --coarse-space: ") + e.what());
  }
}
template <class Set>
void check_coarse_field(const std::string& v, const char* flag, Set set) {
  CoarseOptions o;
  const long x = whole_number(v, flag);
  if (x < INT_MIN || x > INT_MAX)
    throw InputError(std::string("option --") + flag + ": '" + v + "' is out of range");
  set(o, static_cast<int>(x));
  try {
    o.validate();
  } catch (const InputError& e) {
    throw InputError(std::string("option --") + flag + ": " + e.what());
  }
}
void check_coarse_aggregates(const std::string& v) {
  check_coarse_field(v, "coarse-aggregates", [](CoarseOptions& o, int x) { o.aggregates = x; });
}
void check_coarse_smoothing(const std::string& v) {
  check_coarse_field(v, "coarse-smoothing", [](CoarseOptions& o, int x) { o.smoothing_steps = x; });
}

void check_setup_timeout(const std::string& v) {
  if (number_in(v, "setup-timeout", 0, 86400, "(0, 86400]") <= 0)
    throw InputError("launch: --setup-timeout must be in (0, 86400] seconds");
}

// The robust options are checked as RobustOptions checks them (the error names the field).
void check_robust(const std::string& v) {
  try {
    parse_robust_kind(v);
  } catch (const InputError& e) {
    throw InputError(std::string("option --robust: ") + e.what());
  }
}
void check_known_inliers(const std::string& v) {
  try {
    parse_known_inliers(v);
  } catch (const InputError& e) {
    throw InputError(std::string("option --known-inliers: ") + e.what());
  }
}
template <class Set>
void check_robust_field(const std::string& v, const char* flag, Set set) {
  RobustOptions o;
  set(o, number(v, flag));
  try {
    o.validate();
  } catch (const InputError& e) {
    throw InputError(std::string("option --") + flag + ": " + e.what());
  }
}
void check_inlier_threshold(const std::string& v) {
  check_robust_field(v, "inlier-threshold",
                     [](RobustOptions& o, double x) { o.inlier_threshold = x; });
}
void check_inlier_quantile(const std::string& v) {
  check_robust_field(v, "inlier-quantile",
                     [](RobustOptions& o, double x) { o.inlier_quantile = x; });
}
void check_gnc_max_outer(const std::string& v) {
  check_robust_field(v, "gnc-max-outer", [](RobustOptions& o, double x) {
    o.max_outer_iterations = x == static_cast<int>(x) ? static_cast<int>(x) : 0;
  });
}
void check_gnc_mu_step(const std::string& v) {
  check_robust_field(v, "gnc-mu-step", [](RobustOptions& o, double x) { o.mu_step = x; });
}
void check_gnc_mu_step_max(const std::string& v) {
  check_robust_field(v, "gnc-mu-step-max", [](RobustOptions& o, double x) { o.mu_step_max = x; });
}
void check_gnc_inner_rounds(const std::string& v) {
  check_robust_field(v, "gnc-inner-rounds", [](RobustOptions& o, double x) {
    o.inner_max_rounds = x == static_cast<int>(x) ? static_cast<int>(x) : -1;
  });
}
void check_gnc_probes(const std::string& v) {
  check_robust_field(v, "gnc-probes", [](RobustOptions& o, double x) {
    o.recheck_probes = x == static_cast<int>(x) ? static_cast<int>(x) : -1;
  });
}
void check_gnc_probe_ratio(const std::string& v) {
  check_robust_field(v, "gnc-probe-ratio", [](RobustOptions& o, double x) { o.probe_ratio = x; });
}
void check_gnc_cluster_probes(const std::string& v) {
  const double x = number(v, "gnc-cluster-probes");
  if (!(x >= 0 && x == static_cast<double>(static_cast<long>(x)) && x <= 4294967295.0))
    throw InputError("option --gnc-cluster-probes: GncDistributedOptions.cluster_probes = " + v +
                     ": must be an integer >= 0 (0 = none)");
}
void check_gnc_newton_mu_step_max(const std::string& v) {
  check_robust_field(v, "gnc-newton-mu-step-max",
                     [](RobustOptions& o, double x) { o.newton_mu_step_max = x; });
}
void check_gnc_step_trust(const std::string& v) {
  check_robust_field(v, "gnc-step-trust",
                     [](RobustOptions& o, double x) { o.newton_step_trust = x; });
}
void check_gnc_mu_hold(const std::string& v) {
  try {
    parse_mu_step_hold(v);
  } catch (const InputError& e) {
    throw InputError(std::string("option --gnc-mu-hold: ") + e.what());
  }
}
void check_gnc_probe_cut(const std::string& v) {
  try {
    parse_probe_cut(v);
  } catch (const InputError& e) {
    throw InputError(std::string("option --gnc-probe-cut: ") + e.what());
  }
}
void check_gnc_jump_side(const std::string& v) {
  if (v != "both" && v != "beyond")
    throw InputError("option --gnc-jump-side: '" + v + "' is not one of both, beyond");
}
void check_gnc_jump_band_max(const std::string& v) {
  check_robust_field(v, "gnc-jump-band-max",
                     [](RobustOptions& o, double x) { o.jump_band_max = x; });
}
void check_gnc_step_sigma(const std::string& v) {
  if (v != "every" && v != "refine-sigma")
    throw InputError("option --gnc-step-sigma: '" + v + "' is not one of every, refine-sigma");
}
void check_tangent_dots(const std::string& v) {
  cli::parse_tangent_dots(v);
}
void check_gnc_pass_refine(const std::string& v) {
  if (v != "auto" && v != "none")
    throw InputError("option --gnc-pass-refine: '" + v + "' is not one of auto, none");
}
void check_gnc_final_refine(const std::string& v) {
  if (v != "newton" && v != "none")
    throw InputError("option --gnc-final-refine: '" + v + "' is not one of newton, none");
}

}  // namespace

const std::vector<ForwardedFlag>& forwarded_flags() {
  static const std::vector<ForwardedFlag> flags = {
      {"out", "output", true, ForwardTo::kCoordinator, "--out FILE",
       "write the merged poses (g2o, VERTEX lines)", nullptr},
      {"tum", "tum", true, ForwardTo::kCoordinator, "--tum FILE", "write the merged poses (TUM)",
       nullptr},
      {"status-interval", "status-interval", true, ForwardTo::kCoordinator, "--status-interval S",
       "coordinator status line (agents alive, rounds, lagging or lost\n"
       "agents) every S seconds and on changes; 0 = off          [5]",
       check_status_interval},
      {"progress-interval", "progress-interval", true, ForwardTo::kCoordinator,
       "--progress-interval S",
       "at most one progress line per S seconds besides the first,\n"
       "the restarts and the last; 0 = every round the coordinator\n"
       "sees (every round with replicas or rejoin)             [0.1]",
       check_progress_interval},
      {"partition-time", "partition-time", true, ForwardTo::kCoordinator, "--partition-time S",
       "cap the partitioner's search at S seconds of wall time; 0 =\n"
       "none, the preset's own effort (with a cap the partition\n"
       "depends on the machine's speed)                           [0]",
       check_partition_time},
      {"partition-nice", "partition-nice", true, ForwardTo::kCoordinator, "--partition-nice N",
       "the nice of the coordinator's thread that partitions GRAPH\n"
       "while the agents start, relative to the run's, -20..0; it\n"
       "then delays their start-up (needs root or a matching\n"
       "RLIMIT_NICE; JSON partition_nice: what it got)            [0]",
       check_partition_nice},
      {"setup-timeout", "timeout", true, ForwardTo::kBoth, "--setup-timeout S",
       "bound on each set-up wait of a process (the agents'\n"
       "announcements, the assignment, the readiness barrier);\n"
       "large runs on a loaded host read and parse for longer     [30]",
       check_setup_timeout},
      {"robust", "robust", true, ForwardTo::kCoordinator, "--robust none|gnc-tls|pcm-gnc",
       "gnc-tls: reject outlier measurements (graduated non-\n"
       "convexity, truncated least squares), each weighed by the\n"
       "agent of its lower pose id, then solve and certify the\n"
       "kept ones; starts from the known inliers' or the\n"
       "solver's initialization (a vote) unless --init is given;\n"
       "pcm-gnc: agent 0 first drops closures outside the\n"
       "largest pairwise-consistent set (docs/robust.md)    [none]",
       check_robust},
      {"inlier-threshold", "inlier-threshold", true, ForwardTo::kCoordinator,
       "--inlier-threshold C", "residual bound c (0 = chi-square quantile)          [0]",
       check_inlier_threshold},
      {"inlier-quantile", "inlier-quantile", true, ForwardTo::kCoordinator, "--inlier-quantile P",
       "quantile of that bound, 0 = 1 - 1e-4/m               [0]", check_inlier_quantile},
      {"gnc-max-outer", "gnc-max-outer", true, ForwardTo::kCoordinator, "--gnc-max-outer K",
       "most GNC outer steps, >= 1                           [100]", check_gnc_max_outer},
      {"gnc-mu-step", "gnc-mu-step", true, ForwardTo::kCoordinator, "--gnc-mu-step S",
       "mu grows by S per outer step, > 1                    [1.4]", check_gnc_mu_step},
      {"gnc-mu-step-max", "gnc-mu-step-max", true, ForwardTo::kCoordinator, "--gnc-mu-step-max S",
       "after an outer step that moved no weight across 1/2\n"
       "the next step is the last one squared, up to S; 0 =\n"
       "off, else >= --gnc-mu-step                          [0]",
       check_gnc_mu_step_max},
      {"gnc-inner-rounds", "gnc-inner-rounds", true, ForwardTo::kCoordinator,
       "--gnc-inner-rounds K",
       "most rounds of each solve before the final one, 0 = no\n"
       "cap                                                  [5]",
       check_gnc_inner_rounds},
      {"gnc-probes", "gnc-probes", true, ForwardTo::kCoordinator, "--gnc-probes K",
       "most probes after the re-check passes, 0 = none      [2]", check_gnc_probes},
      {"gnc-probe-ratio", "gnc-probe-ratio", true, ForwardTo::kCoordinator, "--gnc-probe-ratio R",
       "a probe takes the kept edges with r^2 above R x their\n"
       "agent's median r^2, > 1                              [5]",
       check_gnc_probe_ratio},
      {"gnc-cluster-probes", "gnc-cluster-probes", true, ForwardTo::kCoordinator,
       "--gnc-cluster-probes K",
       "most cluster probes after the re-check passes (runs of\n"
       "kept closures side by side cut at once; every agent runs\n"
       "the same search), 0 = none                             [0]",
       check_gnc_cluster_probes},
      {"gnc-final-refine", "gnc-final-refine", true, ForwardTo::kCoordinator,
       "--gnc-final-refine newton|none",
       "the final solve of the kept set ends with Newton\n"
       "refinement to --refine-grad-tol                 [newton]",
       check_gnc_final_refine},
      {"gnc-pass-refine", "gnc-pass-refine", true, ForwardTo::kCoordinator,
       "--gnc-pass-refine auto|none",
       "with --refine auto: the inlier passes solved to the\n"
       "tolerance and GNC's weighted solves hand over to\n"
       "Newton refinement where the team's interface fits\n"
       "the interface solves                              [auto]",
       check_gnc_pass_refine},
      {"gnc-newton-mu-step-max", "gnc-newton-mu-step-max", true, ForwardTo::kCoordinator,
       "--gnc-newton-mu-step-max S",
       "while --gnc-mu-step-max is 0, where GNC's weighted\n"
       "solves are Newton steps, mu's step after an outer step\n"
       "that moved no weight across 1/2 is the last one squared,\n"
       "up to S; 0 = none, else > 1                          [4]",
       check_gnc_newton_mu_step_max},
      {"gnc-mu-hold", "gnc-mu-hold", true, ForwardTo::kCoordinator, "--gnc-mu-hold falls|crossings",
       "which weights, at an update,\n"
       "return the bigger step of mu to --gnc-mu-step: those\n"
       "that fell below 1/2, or any that crossed 1/2   [falls]",
       check_gnc_mu_hold},
      {"gnc-step-trust", "gnc-step-trust", true, ForwardTo::kCoordinator, "--gnc-step-trust R",
       "where GNC's weighted solves are Newton steps, weights\n"
       "are updated at a step's point only when it was accepted\n"
       "with actual/predicted decrease >= R, else the same\n"
       "weights are solved by rounds first; [0, 1], 0 = off [0.75]",
       check_gnc_step_trust},
      {"gnc-jump-side", "gnc-jump-side", true, ForwardTo::kCoordinator,
       "--gnc-jump-side both|beyond",
       "which residuals near the bound hold GNC's early end\n"
       "back: within a factor 2 of c^2 on both sides, or only\n"
       "those beyond it                               [beyond]",
       check_gnc_jump_side},
      {"gnc-jump-band-max", "gnc-jump-band-max", true, ForwardTo::kCoordinator,
       "--gnc-jump-band-max M",
       "at small mu the band of GNC's early end widens\n"
       "beyond 2 c^2 to where the weights reach 0, up to\n"
       "M c^2; <= 2: 2 c^2 whatever mu                    [30]",
       check_gnc_jump_band_max},
      {"gnc-probe-cut", "gnc-probe-cut", true, ForwardTo::kCoordinator,
       "--gnc-probe-cut always|after-passes|auto",
       "a re-check probe may cut kept\n"
       "measurements while the rejected set is still GNC's own\n"
       "(always), or only once the passes changed it; auto:\n"
       "after the passes where GNC's solves were Newton steps,\n"
       "always where they were rounds                    [auto]",
       check_gnc_probe_cut},
      {"gnc-step-sigma", "gnc-step-sigma", true, ForwardTo::kCoordinator,
       "--gnc-step-sigma every|refine-sigma",
       "who factors the interface\n"
       "solves' matrix in GNC's weighted Newton steps: every\n"
       "agent, or as --refine-sigma says; the same iterates\n"
       "                                          [refine-sigma]",
       check_gnc_step_sigma},
      {"known-inliers", "known-inliers", true, ForwardTo::kCoordinator,
       "--known-inliers odometry|none", "never reject edges between consecutive ids [odometry]",
       check_known_inliers},
      {"coarse-every", "coarse-every", true, ForwardTo::kCoordinator, "--coarse-every K",
       "two-level rounds: a coarse correction every K-th round,\n"
       "0 = off (docs/irbcd.md, \"Coarse correction\")            [0]",
       check_coarse_every},
      {"coarse-space", "coarse-space", true, ForwardTo::kCoordinator,
       "--coarse-space blocks|smoothed",
       "one rigid motion per block, or K rigid pieces per block\n"
       "blended across their borders                      [blocks]",
       check_coarse_space},
      {"coarse-aggregates", "coarse-aggregates", true, ForwardTo::kCoordinator,
       "--coarse-aggregates K", "smoothed: pieces per block, >= 1                    [4]",
       check_coarse_aggregates},
      {"coarse-smoothing", "coarse-smoothing", true, ForwardTo::kCoordinator,
       "--coarse-smoothing S", "smoothed: smoothing steps of the blend, 0..8         [1]",
       check_coarse_smoothing},
      {"refine", "refine", true, ForwardTo::kCoordinator, "--refine newton|auto|none",
       "after the rounds reach --grad-tol, trust-region Newton\n"
       "steps on the whole problem: CG over neighbour exchanges\n"
       "and all-agent sums (docs/newton-refine.md); auto: where\n"
       "the team's interface fits the exact interface solves,\n"
       "rounds to gradient 30, then always the refinement;\n"
       "elsewhere only where the rounds' last cost decreases say\n"
       "they stopped more than 1e-7 of f above their limit  [auto]",
       check_refine},
      {"refine-grad-tol", "refine-grad-tol", true, ForwardTo::kCoordinator, "--refine-grad-tol T",
       "the refinement stops at ||grad f|| <= T       [1e-6]", check_refine_grad_tol},
      {"refine-rel-tol", "refine-rel-tol", true, ForwardTo::kCoordinator, "--refine-rel-tol F",
       "or after a step that lowered f by < F f           [1e-7]", check_refine_rel_tol},
      {"refine-sigma", "refine-sigma", true, ForwardTo::kCoordinator,
       "--refine-sigma one|every|solve",
       "with the interface solves, agent 0 factors the\n"
       "interface matrix and sends its factor (one), every\n"
       "agent factors it at every point (every), or agent 0\n"
       "alone factors it and sends each agent its part of\n"
       "every solve (solve); the same iterates         [solve]",
       check_refine_sigma},
      {"tangent-dots", "tangent-dots", true, ForwardTo::kCoordinator,
       "--tangent-dots split|sequential",
       "the tangent preconditioner's\n"
       "backward dot products as four partial sums, or CHOLMOD's\n"
       "sequential sums (its bits)                       [split]",
       check_tangent_dots},
      {"setup-at-once", "setup-at-once", true, ForwardTo::kCoordinator, "--setup-at-once K",
       "at most K agents in the distributed initialisation's\n"
       "local chordal solve at once (the set-up's memory peak);\n"
       "0 = all at once                                      [8]",
       check_setup_at_once},
      {"reference-cost", "reference-cost", true, ForwardTo::kCoordinator, "--reference-cost F",
       "the graph's optimal cost f*, known from elsewhere\n"
       "(tessera solve --algorithm centralized): the summary\n"
       "reports rel_gap_to_reference = (cost - F) / F, F > 0",
       check_reference_cost},
      {"rejected", "rejected", true, ForwardTo::kCoordinator, "--rejected FILE",
       "write the rejected edge indices (from 0 over the EDGE\n"
       "lines), one a line",
       nullptr},
  };
  return flags;
}

const ForwardedFlag* find_forwarded_flag(const std::string& name) {
  for (const ForwardedFlag& f : forwarded_flags())
    if (name == f.name) return &f;
  return nullptr;
}

std::string forwarded_flags_help() {
  constexpr std::size_t kTextColumn = 23;  // as the rest of launch's help
  std::string out;
  for (const ForwardedFlag& f : forwarded_flags()) {
    std::string line = std::string("  ") + f.usage;
    // A long usage keeps two blanks before the text, as the rest of the help.
    line += std::string(line.size() + 2 <= kTextColumn ? kTextColumn - line.size() : 2, ' ');
    for (const char* c = f.help; *c; ++c) {
      line += *c;
      if (*c == '\n') line += std::string(kTextColumn, ' ');
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace tessera::launch
