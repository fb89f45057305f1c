#include "transport/assignment_options.hpp"

#include <string>
#include <tessera/robust/robust_options.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera::transport {

void write_run_options(const agent::RunOptions& o, wire::PartitionAssignment& asg) {
  asg.algorithm(o.algorithm);
  asg.initialization(o.initialization);
  asg.rank(o.rank);
  asg.max_rounds(o.max_rounds);
  asg.grad_norm_tolerance(o.grad_norm_tolerance);
  asg.relative_cost_tolerance(o.relative_cost_tolerance);
  asg.seed(o.seed);
  asg.certify(o.certify);
  asg.coarse_every(o.coarse_every);
  asg.coarse_aggregates(o.coarse_aggregates);
  asg.coarse_smoothing(o.coarse_smoothing);
  asg.refine(o.refine);
  asg.refine_grad_tol(o.refine_grad_tol);
  asg.refine_rel_tol(o.refine_rel_tol);
  asg.refine_sigma(o.refine_sigma);
  asg.tangent_sequential_dots(!o.tangent_split_dots);
  if (o.robust.kind == RobustKind::kNone) return;
  const RobustOptions& r = o.robust;
  asg.robust(robust_kind_name(r.kind));
  asg.inlier_threshold(r.inlier_threshold);
  asg.inlier_quantile(r.inlier_quantile);
  asg.gnc_max_outer(static_cast<std::uint32_t>(r.max_outer_iterations));
  asg.gnc_mu_step(r.mu_step);
  asg.gnc_inner_max_rounds(static_cast<std::uint32_t>(r.inner_max_rounds));
  asg.known_inliers(known_inliers_name(r.known_inliers));
  asg.gnc_known_start(o.gnc_known_start);
  asg.gnc_readmission_passes(static_cast<std::uint32_t>(r.readmission_passes));
  asg.gnc_recheck_probes(static_cast<std::uint32_t>(r.recheck_probes));
  asg.gnc_probe_ratio(r.probe_ratio);
  asg.gnc_final_refine(r.final_refine);
  asg.gnc_cluster_probes(static_cast<std::uint32_t>(o.gnc_cluster_probes));
  asg.gnc_pass_refine(r.refine_passes);
  asg.gnc_mu_step_max(r.mu_step_max);
  asg.gnc_newton_mu_step_max(r.newton_mu_step_max);
  asg.gnc_mu_hold(mu_step_hold_name(r.mu_step_hold));
  asg.gnc_step_trust(r.newton_step_trust);
  asg.gnc_jump_band_inside(r.jump_band_inside);
  asg.gnc_jump_band_max(r.jump_band_max);
  asg.gnc_probe_cut(probe_cut_name(r.probe_cut));
  asg.gnc_step_sigma_every(r.step_sigma_every_agent);
}

agent::RunOptions run_options_of(const wire::PartitionAssignment& asg) {
  agent::RunOptions ro;
  ro.algorithm = asg.algorithm();
  ro.initialization = asg.initialization();
  ro.rank = asg.rank();
  ro.max_rounds = asg.max_rounds();
  ro.grad_norm_tolerance = asg.grad_norm_tolerance();
  ro.relative_cost_tolerance = asg.relative_cost_tolerance();
  ro.seed = asg.seed();
  ro.certify = asg.certify();
  ro.coarse_every = asg.coarse_every();
  ro.coarse_aggregates = asg.coarse_aggregates();
  ro.coarse_smoothing = asg.coarse_smoothing();
  ro.refine = asg.refine();
  ro.refine_grad_tol = asg.refine_grad_tol();
  ro.refine_rel_tol = asg.refine_rel_tol();
  ro.refine_sigma = asg.refine_sigma();
  ro.tangent_split_dots = !asg.tangent_sequential_dots();
  if (asg.robust().empty()) return ro;
  RobustOptions& r = ro.robust;
  r.kind = parse_robust_kind(asg.robust());
  r.inlier_threshold = asg.inlier_threshold();
  r.inlier_quantile = asg.inlier_quantile();
  r.max_outer_iterations = static_cast<int>(asg.gnc_max_outer());
  r.mu_step = asg.gnc_mu_step();
  r.inner_max_rounds = static_cast<int>(asg.gnc_inner_max_rounds());
  r.known_inliers = parse_known_inliers(asg.known_inliers());
  r.readmission_passes = static_cast<int>(asg.gnc_readmission_passes());
  r.recheck_probes = static_cast<int>(asg.gnc_recheck_probes());
  r.probe_ratio = asg.gnc_probe_ratio();
  r.final_refine = asg.gnc_final_refine();
  r.refine_passes = asg.gnc_pass_refine();
  r.mu_step_max = asg.gnc_mu_step_max();
  r.newton_mu_step_max = asg.gnc_newton_mu_step_max();
  try {
    if (!asg.gnc_mu_hold().empty()) r.mu_step_hold = parse_mu_step_hold(asg.gnc_mu_hold());
  } catch (const InputError& e) {
    throw InputError(std::string("PartitionAssignment.gnc_mu_hold: ") + e.what());
  }
  r.newton_step_trust = asg.gnc_step_trust();
  r.jump_band_inside = asg.gnc_jump_band_inside();
  r.jump_band_max = asg.gnc_jump_band_max();
  try {
    if (!asg.gnc_probe_cut().empty()) r.probe_cut = parse_probe_cut(asg.gnc_probe_cut());
  } catch (const InputError& e) {
    throw InputError(std::string("PartitionAssignment.gnc_probe_cut: ") + e.what());
  }
  r.step_sigma_every_agent = asg.gnc_step_sigma_every();
  r.validate();
  ro.gnc_known_start = asg.gnc_known_start();
  ro.gnc_cluster_probes = static_cast<int>(asg.gnc_cluster_probes());
  return ro;
}

}  // namespace tessera::transport
