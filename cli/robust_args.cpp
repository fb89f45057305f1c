#include "robust_args.hpp"

#include <tessera/util/input_error.hpp>

namespace tessera::cli {

const char* const kRobustValued[] = {"robust",
                                     "inlier-threshold",
                                     "inlier-quantile",
                                     "gnc-max-outer",
                                     "gnc-mu-step",
                                     "gnc-inner-rounds",
                                     "known-inliers",
                                     "rejected",
                                     "gnc-inner-iterations",
                                     "gnc-probes",
                                     "gnc-probe-ratio",
                                     "gnc-final-refine",
                                     "gnc-swap-probes",
                                     "gnc-pass-refine",
                                     "gnc-mu-step-max",
                                     "gnc-jump-side",
                                     "gnc-jump-band-max",
                                     "gnc-probe-cut",
                                     "gnc-newton-mu-step-max",
                                     "gnc-step-sigma",
                                     "gnc-mu-hold",
                                     "gnc-step-trust",
                                     nullptr};

const char* const kRobustHelp =
    "\n"
    "Outlier rejection (docs/robust.md):\n"
    "  --robust none|gnc-tls|pcm-gnc   none: plain least squares (default); gnc-tls: graduated\n"
    "                            non-convexity with a truncated least-squares cost, then the\n"
    "                            certified solve of the kept measurements (--certify for the\n"
    "                            distributed algorithms); centralized: starts from\n"
    "                            --init odometry; distributed: from the known inliers' or\n"
    "                            the solver's initialization, whichever has the lower TLS\n"
    "                            cost; --init given: from that one\n"
    "                            pcm-gnc: closures outside the largest pairwise-consistent\n"
    "                            set start GNC at weight 0 (distributed: agent 0 runs the\n"
    "                            check on the values the others send it)\n"
    "  --inlier-threshold C      residual bound c: TLS charges min(r^2, c^2), r^2 = the edge's\n"
    "                            term of the objective (default 0 = from the chi-square\n"
    "                            quantile below, d(d+1)/2 degrees of freedom)\n"
    "  --inlier-quantile P       chi-square probability of that default, in (0, 1); 0 =\n"
    "                            1 - 1e-4/m for m rejectable edges (union bound) [0]\n"
    "  --gnc-max-outer K         most outer steps, >= 1 [100]\n"
    "  --gnc-mu-step S           mu grows by S per outer step, > 1 [1.4]\n"
    "  --gnc-mu-step-max S       distributed: after an outer step that moved no weight across\n"
    "                            1/2, the next step is the last one squared, up to S; 0 = off,\n"
    "                            else >= --gnc-mu-step [0]\n"
    "  --gnc-inner-rounds K      distributed: most rounds of each solve before the final\n"
    "                            one (first and weighted), 0 = no cap [5]\n"
    "  --gnc-inner-iterations K  centralized: most trust-region iterations of each solve\n"
    "                            before the re-check passes (first and weighted), 0 = no cap [0]\n"
    "  --gnc-probes K            most probes after the re-check passes (the kept edges far\n"
    "                            above the median residual leave together, rejected ones within\n"
    "                            4 c^2 come back; the result stays only if the TLS cost fell),\n"
    "                            0 = none [2]; centralized: besides these, return probes\n"
    "                            (rejected edges within 4 c^2 back together, then, with\n"
    "                            --gnc-cluster-probes, one at a time), one or that budget;\n"
    "                            0 = no probe of either kind\n"
    "  --gnc-probe-ratio R       a probe takes the kept edges with r^2 above R x the median r^2\n"
    "                            of the kept edges (distributed: those their agent weighs), > 1 "
    "[5]\n"
    "  --gnc-swap-probes K       centralized: most swap probes after the other probes (a kept\n"
    "                            edge with r^2 >= c^2/4 leaves, a rejected one within 10 c^2\n"
    "                            sharing a pose with it comes back, or none when there is none\n"
    "                            and its r^2 is above --gnc-probe-ratio x the kept median; kept\n"
    "                            only if the TLS cost fell), 0 = none [3]\n"
    "  --gnc-final-refine newton|none   distributed: the final solve of the kept set ends with\n"
    "                            Newton refinement to --refine-grad-tol (runs without\n"
    "                            --certify too) [newton]\n"
    "  --gnc-pass-refine auto|none   distributed, with --refine auto: inlier passes solved to\n"
    "                            the tolerance and GNC's weighted solves hand over to Newton\n"
    "                            refinement where the team's interface fits the interface\n"
    "                            solves [auto]\n"
    "  --gnc-jump-side both|beyond   distributed: which residuals near the bound hold\n"
    "                            GNC's early end back: within a factor 2 of c^2 on both sides,\n"
    "                            or only those beyond it (the passes judge the ones within it on\n"
    "                            the kept set) [beyond]\n"
    "  --gnc-jump-band-max M     distributed: at small mu the band of GNC's early end\n"
    "                            widens beyond 2 c^2 to where the weights reach 0, up to M c^2;\n"
    "                            <= 2: 2 c^2 whatever mu [30]\n"
    "  --gnc-probe-cut always|after-passes|auto   distributed: whether a re-check\n"
    "                            probe may cut kept measurements while the rejected set is\n"
    "                            still GNC's own (always), or only once the re-check passes\n"
    "                            changed it (before that it only brings back the return band);\n"
    "                            auto: after the passes where GNC's weighted solves were\n"
    "                            Newton steps, always where they were rounds [auto]\n"
    "  --gnc-newton-mu-step-max S   distributed: while --gnc-mu-step-max is 0, where\n"
    "                            GNC's weighted solves are Newton steps, mu's step after an\n"
    "                            outer step that moved no weight across 1/2 is the last one\n"
    "                            squared, up to S; 0 = none, else > 1 [4]\n"
    "  --gnc-step-trust R        distributed: where GNC's weighted solves are Newton steps,\n"
    "                            the weights are updated at a step's point only when it was\n"
    "                            accepted with actual/predicted decrease >= R; otherwise\n"
    "                            the same weights are solved by rounds from the step's\n"
    "                            start first; [0, 1], 0 = off [0.75]\n"
    "  --gnc-mu-hold falls|crossings   distributed: which weights, at an update, return\n"
    "                            the bigger step of mu to --gnc-mu-step: those that fell below\n"
    "                            1/2 (left the inlier set), or any that crossed 1/2 [falls]\n"
    "  --gnc-step-sigma every|refine-sigma   distributed: who factors the interface\n"
    "                            solves' matrix in GNC's weighted Newton steps: every agent\n"
    "                            (no wait for agent 0's solve), or as --refine-sigma says; the\n"
    "                            same iterates [refine-sigma]\n"
    "  --known-inliers odometry|none   never reject edges between consecutive ids [odometry]\n"
    "  --rejected FILE           write the rejected edge indices (from 0 over the EDGE lines)\n";

const char* final_refine_name(const RobustOptions& options) {
  return options.final_refine ? "newton" : "none";
}

bool parse_final_refine(const std::string& name) {
  if (name == "newton") return true;
  if (name == "none") return false;
  throw InputError("option --gnc-final-refine: '" + name + "' is not one of newton, none");
}

RobustOptions parse_robust_options(const Arguments& args) {
  RobustOptions o;
  o.kind = parse_robust_kind(args.get_or("robust", robust_kind_name(o.kind)));
  o.inlier_threshold = args.get_double("inlier-threshold", o.inlier_threshold);
  o.inlier_quantile = args.get_double("inlier-quantile", o.inlier_quantile);
  o.max_outer_iterations = static_cast<int>(args.get_long("gnc-max-outer", o.max_outer_iterations));
  o.mu_step = args.get_double("gnc-mu-step", o.mu_step);
  o.mu_step_max = args.get_double("gnc-mu-step-max", o.mu_step_max);
  o.inner_max_rounds = static_cast<int>(args.get_long("gnc-inner-rounds", o.inner_max_rounds));
  o.inner_max_iterations =
      static_cast<int>(args.get_long("gnc-inner-iterations", o.inner_max_iterations));
  o.recheck_probes = static_cast<int>(args.get_long("gnc-probes", o.recheck_probes));
  o.probe_ratio = args.get_double("gnc-probe-ratio", o.probe_ratio);
  o.swap_probes = static_cast<int>(args.get_long("gnc-swap-probes", o.swap_probes));
  o.final_refine = parse_final_refine(args.get_or("gnc-final-refine", final_refine_name(o)));
  const std::string pass_refine = args.get_or("gnc-pass-refine", o.refine_passes ? "auto" : "none");
  if (pass_refine != "auto" && pass_refine != "none")
    throw InputError("option --gnc-pass-refine: '" + pass_refine + "' is not one of auto, none");
  o.refine_passes = pass_refine == "auto";
  o.known_inliers =
      parse_known_inliers(args.get_or("known-inliers", known_inliers_name(o.known_inliers)));
  // The distributed GNC's own (RobustOptions' fields of the same names); every agent of a DDS
  // run takes them from the coordinator's assignment (transport/assignment_options.hpp).
  const std::string jump_side =
      args.get_or("gnc-jump-side", o.jump_band_inside ? "both" : "beyond");
  if (jump_side != "both" && jump_side != "beyond")
    throw InputError("option --gnc-jump-side: '" + jump_side + "' is not one of both, beyond");
  o.jump_band_inside = jump_side == "both";
  o.jump_band_max = args.get_double("gnc-jump-band-max", o.jump_band_max);
  try {
    o.probe_cut = parse_probe_cut(args.get_or("gnc-probe-cut", probe_cut_name(o.probe_cut)));
  } catch (const InputError& e) {
    throw InputError(std::string("option --gnc-probe-cut: ") + e.what());
  }
  const std::string step_sigma =
      args.get_or("gnc-step-sigma", o.step_sigma_every_agent ? "every" : "refine-sigma");
  if (step_sigma != "every" && step_sigma != "refine-sigma")
    throw InputError("option --gnc-step-sigma: '" + step_sigma +
                     "' is not one of every, refine-sigma");
  o.step_sigma_every_agent = step_sigma == "every";
  try {
    o.mu_step_hold =
        parse_mu_step_hold(args.get_or("gnc-mu-hold", mu_step_hold_name(o.mu_step_hold)));
  } catch (const InputError& e) {
    throw InputError(std::string("option --gnc-mu-hold: ") + e.what());
  }
  o.newton_mu_step_max = args.get_double("gnc-newton-mu-step-max", o.newton_mu_step_max);
  o.newton_step_trust = args.get_double("gnc-step-trust", o.newton_step_trust);
  try {
    o.validate();
  } catch (const InputError& e) {
    // Name the flag the user typed as well as the field.
    const std::string what = e.what();
    const char* flag =
        what.find("inlier_threshold") != std::string::npos       ? "--inlier-threshold"
        : what.find("inlier_quantile") != std::string::npos      ? "--inlier-quantile"
        : what.find("max_outer") != std::string::npos            ? "--gnc-max-outer"
        : what.find("newton_mu_step_max") != std::string::npos   ? "--gnc-newton-mu-step-max"
        : what.find("newton_step_trust") != std::string::npos    ? "--gnc-step-trust"
        : what.find("mu_step_max") != std::string::npos          ? "--gnc-mu-step-max"
        : what.find("mu_step") != std::string::npos              ? "--gnc-mu-step"
        : what.find("inner_max_rounds") != std::string::npos     ? "--gnc-inner-rounds"
        : what.find("inner_max_iterations") != std::string::npos ? "--gnc-inner-iterations"
        : what.find("recheck_probes") != std::string::npos       ? "--gnc-probes"
        : what.find("swap_probes") != std::string::npos          ? "--gnc-swap-probes"
        : what.find("probe_ratio") != std::string::npos          ? "--gnc-probe-ratio"
                                                                 : "--robust";
    throw InputError("option " + std::string(flag) + ": " + what);
  }
  if (o.kind == RobustKind::kNone && args.has("rejected"))
    throw InputError("option --rejected: needs --robust gnc-tls or pcm-gnc");
  return o;
}

void add_robust_fields(JsonObject& json, const RobustSummary& s) {
  json.add("robust", robust_kind_name(s.options.kind))
      .add("outer_iterations", s.outer_iterations)
      .add("total_iterations", s.total_iterations)
      .add("inliers", s.measurements - s.rejected.size())
      .add("outliers", s.rejected.size())
      .add("rejected", s.rejected)
      .add("inlier_threshold_squared", s.threshold_squared)
      .add("known_inliers", known_inliers_name(s.options.known_inliers))
      .add("gnc_mu_step", s.options.mu_step)
      .add("gnc_mu_step_max", s.options.mu_step_max)
      .add("gnc_newton_mu_step_max", s.options.newton_mu_step_max)
      .add("gnc_mu_hold", mu_step_hold_name(s.options.mu_step_hold))
      .add("gnc_step_trust", s.options.newton_step_trust)
      .add("gnc_jump_side", s.options.jump_band_inside ? "both" : "beyond")
      .add("gnc_jump_band_max", s.options.jump_band_max)
      .add("gnc_probe_cut", probe_cut_name(s.options.probe_cut))
      .add("weights_converged", s.weights_converged)
      .add("readmitted", s.readmitted)
      .add("probes", s.probes)
      .add("probes_kept", s.probes_kept)
      .add("gnc_final_refine", final_refine_name(s.options));
  if (s.total_cg_iterations >= 0) json.add("total_cg_iterations", s.total_cg_iterations);
  if (s.swap_probes >= 0)
    json.add("swap_probes", s.swap_probes).add("swap_probes_kept", s.swap_probes_kept);
}

void write_rejected(const std::string& path, const std::vector<std::size_t>& rejected) {
  std::string text;
  for (std::size_t e : rejected) text += std::to_string(e) + "\n";
  write_output(path, text);
}

void add_distributed_robust_fields(JsonObject& json, const RobustOptions& options,
                                   const GncAgentResult& gnc, long long rounds,
                                   std::size_t measurements, long long final_refine_steps,
                                   long long final_solve_stages) {
  RobustSummary rs;
  rs.options = options;
  rs.outer_iterations = gnc.outer_iterations;
  rs.total_iterations = static_cast<int>(rounds);
  rs.measurements = measurements;
  rs.rejected = gnc.rejected;
  rs.threshold_squared = gnc.threshold_squared;
  rs.weights_converged = gnc.weights_converged;
  rs.readmitted = gnc.readmitted;
  rs.probes = gnc.probes;
  rs.probes_kept = gnc.probes_kept;
  add_robust_fields(json, rs);
  json.add("gnc_step_sigma", options.step_sigma_every_agent ? "every" : "refine-sigma")
      .add("total_rounds", rounds)
      .add("gnc_refine_steps", gnc.refine_message_steps)
      .add("gnc_exchange_steps", gnc.exchange_steps)
      .add("final_refine_steps", final_refine_steps)
      .add("solve_stages", gnc.solve_stages + final_solve_stages)
      .add("message_steps_total",
           message_steps(gnc, rounds, final_solve_stages, final_refine_steps));
}

}  // namespace tessera::cli
