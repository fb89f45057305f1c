// The run's options on their way through the coordinator's assignment
// (transport/assignment_options.hpp): what the coordinator writes every agent reads back, field
// by field, the solve-only options that launch now forwards included (--tangent-dots and the
// distributed GNC's --gnc-mu-hold, --gnc-step-trust, --gnc-newton-mu-step-max, --gnc-jump-side,
// --gnc-jump-band-max, --gnc-probe-cut, --gnc-step-sigma); absent flags keep core's defaults; a
// value the agents do not know is an InputError naming its field. No process is started.

#include <gtest/gtest.h>

#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/robust/robust_options.hpp>

#include "runtime/agent_checkpoint.hpp"
#include "runtime/round_loop.hpp"
#include "test_support.hpp"
#include "transport/assignment_options.hpp"

namespace tessera {
namespace {

// Every option away from its default.
agent::RunOptions tuned() {
  agent::RunOptions o;
  o.algorithm = "rbcd++";
  o.initialization = "distributed";
  o.rank = 6;
  o.max_rounds = 77;
  o.grad_norm_tolerance = 0.003;
  o.relative_cost_tolerance = 1e-9;
  o.seed = 9;
  o.certify = true;
  o.coarse_every = 3;
  o.coarse_aggregates = 5;
  o.coarse_smoothing = 2;
  o.refine = "newton";
  o.refine_grad_tol = 1e-5;
  o.refine_rel_tol = 1e-8;
  o.refine_sigma = "one";
  o.tangent_split_dots = false;
  RobustOptions& r = o.robust;
  r.kind = RobustKind::kGncTls;
  r.inlier_threshold = 2.5;
  r.inlier_quantile = 0.9;
  r.max_outer_iterations = 40;
  r.mu_step = 1.6;
  r.inner_max_rounds = 7;
  r.known_inliers = KnownInliers::kNone;
  r.readmission_passes = 3;
  r.recheck_probes = 4;
  r.probe_ratio = 6;
  r.final_refine = false;
  r.refine_passes = false;
  r.mu_step_max = 3;
  r.newton_mu_step_max = 9;
  r.mu_step_hold = MuStepHold::kCrossings;
  r.newton_step_trust = 0.5;
  r.jump_band_inside = true;
  r.jump_band_max = 12;
  r.probe_cut = ProbeCut::kAlways;
  r.step_sigma_every_agent = true;
  o.gnc_known_start = false;
  o.gnc_cluster_probes = 11;
  return o;
}

agent::RunOptions round_trip(const agent::RunOptions& o) {
  wire::PartitionAssignment asg;
  transport::write_run_options(o, asg);
  return transport::run_options_of(asg);
}

void expect_same_robust(const RobustOptions& a, const RobustOptions& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.inlier_threshold, b.inlier_threshold);
  EXPECT_EQ(a.inlier_quantile, b.inlier_quantile);
  EXPECT_EQ(a.max_outer_iterations, b.max_outer_iterations);
  EXPECT_EQ(a.mu_step, b.mu_step);
  EXPECT_EQ(a.inner_max_rounds, b.inner_max_rounds);
  EXPECT_EQ(a.known_inliers, b.known_inliers);
  EXPECT_EQ(a.readmission_passes, b.readmission_passes);
  EXPECT_EQ(a.recheck_probes, b.recheck_probes);
  EXPECT_EQ(a.probe_ratio, b.probe_ratio);
  EXPECT_EQ(a.final_refine, b.final_refine);
  EXPECT_EQ(a.refine_passes, b.refine_passes);
  EXPECT_EQ(a.mu_step_max, b.mu_step_max);
  EXPECT_EQ(a.newton_mu_step_max, b.newton_mu_step_max);
  EXPECT_EQ(a.mu_step_hold, b.mu_step_hold);
  EXPECT_EQ(a.newton_step_trust, b.newton_step_trust);
  EXPECT_EQ(a.jump_band_inside, b.jump_band_inside);
  EXPECT_EQ(a.jump_band_max, b.jump_band_max);
  EXPECT_EQ(a.probe_cut, b.probe_cut);
  EXPECT_EQ(a.step_sigma_every_agent, b.step_sigma_every_agent);
}

void expect_same(const agent::RunOptions& a, const agent::RunOptions& b) {
  EXPECT_EQ(a.algorithm, b.algorithm);
  EXPECT_EQ(a.initialization, b.initialization);
  EXPECT_EQ(a.rank, b.rank);
  EXPECT_EQ(a.max_rounds, b.max_rounds);
  EXPECT_EQ(a.grad_norm_tolerance, b.grad_norm_tolerance);
  EXPECT_EQ(a.relative_cost_tolerance, b.relative_cost_tolerance);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.certify, b.certify);
  EXPECT_EQ(a.coarse_every, b.coarse_every);
  EXPECT_EQ(a.coarse_aggregates, b.coarse_aggregates);
  EXPECT_EQ(a.coarse_smoothing, b.coarse_smoothing);
  EXPECT_EQ(a.refine, b.refine);
  EXPECT_EQ(a.refine_grad_tol, b.refine_grad_tol);
  EXPECT_EQ(a.refine_rel_tol, b.refine_rel_tol);
  EXPECT_EQ(a.refine_sigma, b.refine_sigma);
  EXPECT_EQ(a.tangent_split_dots, b.tangent_split_dots);
  EXPECT_EQ(a.gnc_known_start, b.gnc_known_start);
  EXPECT_EQ(a.gnc_cluster_probes, b.gnc_cluster_probes);
  expect_same_robust(a.robust, b.robust);
}

TEST(AssignmentOptions, EveryAgentReadsBackWhatTheCoordinatorWrote) {
  const agent::RunOptions o = tuned();
  expect_same(round_trip(o), o);
  // The factor budget is each host's own, never the coordinator's.
  agent::RunOptions capped = o;
  capped.max_factor_entries = 12345;
  EXPECT_EQ(round_trip(capped).max_factor_entries, 0u);
}

TEST(AssignmentOptions, AbsentFlagsKeepCoresDefaults) {
  const agent::RunOptions plain;
  expect_same(round_trip(plain), plain);
  agent::RunOptions robust;
  robust.robust.kind = RobustKind::kGncTls;
  expect_same(round_trip(robust), robust);
  // A run that leaves a field empty (or is not robust) gets core's default there.
  wire::PartitionAssignment asg;
  transport::write_run_options(robust, asg);
  asg.gnc_mu_hold("");
  asg.gnc_probe_cut("");
  const RobustOptions back = transport::run_options_of(asg).robust;
  EXPECT_EQ(back.mu_step_hold, RobustOptions{}.mu_step_hold);
  EXPECT_EQ(back.probe_cut, RobustOptions{}.probe_cut);
  EXPECT_TRUE(transport::run_options_of(wire::PartitionAssignment{}).tangent_split_dots);
}

TEST(AssignmentOptions, TheAgentsSolverTakesTheForwardedValues) {
  agent::RunOptions o;
  EXPECT_TRUE(agent::distributed_options_of(o).block_update.tangent_split_dots);
  o.tangent_split_dots = false;
  EXPECT_FALSE(agent::distributed_options_of(round_trip(o)).block_update.tangent_split_dots);
}

TEST(AssignmentOptions, AnUnknownValueNamesItsField) {
  agent::RunOptions robust;
  robust.robust.kind = RobustKind::kGncTls;
  wire::PartitionAssignment asg;
  transport::write_run_options(robust, asg);
  wire::PartitionAssignment hold = asg;
  hold.gnc_mu_hold("sometimes");
  const std::string e = test::input_error_of([&] { transport::run_options_of(hold); });
  EXPECT_NE(e.find("gnc_mu_hold"), std::string::npos) << e;
  EXPECT_NE(e.find("sometimes"), std::string::npos) << e;
  wire::PartitionAssignment trust = asg;
  trust.gnc_step_trust(2);
  EXPECT_NE(
      test::input_error_of([&] { transport::run_options_of(trust); }).find("newton_step_trust"),
      std::string::npos);
  wire::PartitionAssignment newton = asg;
  newton.gnc_newton_mu_step_max(0.5);
  EXPECT_NE(
      test::input_error_of([&] { transport::run_options_of(newton); }).find("newton_mu_step_max"),
      std::string::npos);
}

TEST(AssignmentOptions, ARestartedAgentsCheckpointKeepsTheTangentDots) {
  agent::AgentLocalData local;
  local.d = 2;
  local.num_poses = 1;
  local.owner = {0};
  local.options.tangent_split_dots = false;
  const agent::AgentCheckpoint back =
      agent::decode_checkpoint(agent::encode_checkpoint("dots", local, {}), "test");
  EXPECT_FALSE(back.local.options.tangent_split_dots);
}

}  // namespace
}  // namespace tessera
