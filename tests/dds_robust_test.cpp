// Robust (GNC-TLS) distributed solves over DDS: separate agent processes run the same state
// machine as the in-process engine (robust/gnc_agent.hpp), so the same outer steps, rounds,
// rejected set and cost.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <string>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <utility>
#include <vector>

#include "dds_process_support.hpp"
#include "gnc_fixtures.hpp"

namespace tessera::test::dds {
namespace {

// A JSON array of integers of a flat summary (e.g. "rejected" or the labels' "outliers").
std::vector<std::size_t> json_array(const std::string& json, const std::string& name) {
  std::smatch m;
  std::vector<std::size_t> out;
  if (!std::regex_search(json, m, std::regex("\"" + name + "\": \\[([^\\]]*)\\]"))) return out;
  std::istringstream list(m[1].str());
  for (std::string v; std::getline(list, v, ',');)
    if (v.find_first_of("0123456789") != std::string::npos) out.push_back(std::stoul(v));
  return out;
}

std::vector<std::size_t> lines_of(const std::string& path) {
  std::vector<std::size_t> out;
  std::ifstream f(path);
  for (std::string line; std::getline(f, line);)
    if (!line.empty()) out.push_back(std::stoul(line));
  return out;
}

// 3 agent processes on `graph` in `dir` (sequential partition: one robot each, run id
// `run`) with `--robust kind`, the certificate and `extra`.
FinishedRun robust_run(const std::string& dir, const std::string& graph, const std::string& run,
                       int domain, const std::string& kind,
                       const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {
      "--timeout", "20", "--run-timeout", "120",      "--partition", "sequential",
      "--seed",    "7",  "--certify",     "--robust", kind};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_and_read(dir, graph, 3, run, domain, args, 120);
}

struct RobustRun {
  std::string dir, graph, summary;
  std::vector<std::size_t> labels;
  std::vector<int> assignment;
};

// A 216-pose 3D grid of 3 robots with 25 % wrong loop closures, solved by 3 agent processes
// (sequential partition: one robot each) with GNC-TLS and the certificate.
RobustRun robust_dds_run(int domain, const std::vector<std::string>& extra = {}) {
  RobustRun r;
  r.dir = temp_dir();
  r.graph = generate_graph(r.dir + "/graph.g2o",
                           "--kind grid3d --poses 216 --robots 3 --seed 4 --outliers 0.25 "
                           "--labels " +
                               r.dir + "/labels.json");
  r.labels = json_array(slurp(r.dir + "/labels.json"), "outliers");
  const std::string run = "robust-" + std::to_string(getpid()) + "-" + std::to_string(domain);
  std::vector<std::string> args = {"--rejected", r.dir + "/rejected.txt"};
  args.insert(args.end(), extra.begin(), extra.end());
  FinishedRun done = robust_run(r.dir, r.graph, run, domain, "gnc-tls", args);
  r.summary = std::move(done.summary);
  r.assignment = std::move(done.assignment);
  return r;
}

// dpgo's measurement CSV of a generated graph whose robots hold `per_robot` poses each;
// `flagged` measurements get is_known_inlier = 1.
std::string dpgo_csv_of(const PoseGraph& g, std::size_t per_robot,
                        const std::vector<std::size_t>& flagged = {}) {
  std::string csv =
      "robot_src,pose_src,robot_dst,pose_dst,qx,qy,qz,qw,tx,ty,tz,kappa,tau,is_known_inlier,"
      "weight\n";
  for (std::size_t e = 0; e < g.measurements.size(); ++e) {
    const Measurement& m = g.measurements[e];
    const Eigen::Quaterniond q(Eigen::Matrix3d(m.R));
    const int known = std::count(flagged.begin(), flagged.end(), e) > 0 ? 1 : 0;
    char row[512];
    std::snprintf(row, sizeof row,
                  "%zu,%zu,%zu,%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,1\n",
                  m.i / per_robot, m.i % per_robot, m.j / per_robot, m.j % per_robot, q.x(), q.y(),
                  q.z(), q.w(), m.t(0), m.t(1), m.t(2), m.kappa, m.tau, known);
    csv += row;
  }
  return csv;
}

// The DDS run's summary `json` reports what the in-process engine did (`ref`): the same outer
// steps, rounds and rejected set, and the same cost to 1e-12 relative.
void expect_same_run(const std::string& json, const GncDistributedResult& ref) {
  EXPECT_EQ(json_field(json, "outer_iterations"), ref.outer_iterations) << json;
  EXPECT_EQ(json_field(json, "rounds"), ref.total_rounds) << json;
  EXPECT_EQ(json_array(json, "rejected"), ref.rejected) << json;
  EXPECT_NEAR(json_field(json, "cost"), ref.final_solve.cost, 1e-12 * ref.final_solve.cost) << json;
}

GncDistributedOptions in_process_options() {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.seed = 7;
  o.solver.certify = true;
  return o;
}

TEST(DdsRobust, IteratesAndRejectedSetEqualTheInProcessEngine) {
  const RobustRun dds = robust_dds_run(42);
  const PoseGraph g = read_g2o(dds.graph);
  ASSERT_EQ(dds.assignment.size(), g.num_poses);
  ASSERT_FALSE(dds.labels.empty());

  const GncDistributedResult ref = solve_gnc_distributed(g, dds.assignment, in_process_options());
  ASSERT_GT(ref.outer_iterations, 3) << "the outliers should take a few outer steps";
  ASSERT_TRUE(ref.final_solve.certified.value_or(false));

  EXPECT_EQ(json_field(dds.summary, "outer_iterations"), ref.outer_iterations) << dds.summary;
  EXPECT_EQ(json_field(dds.summary, "rounds"), ref.total_rounds) << dds.summary;
  // GNC's weighted solves are Newton steps on this layout (RobustOptions::gnc_refine_steps), the
  // same ones over DDS.
  EXPECT_GT(ref.refine_message_steps, 0);
  EXPECT_EQ(json_field(dds.summary, "gnc_refine_steps"), ref.refine_message_steps) << dds.summary;
  // GNC's own exchanges and every wait for peers in all: the same count over DDS. The poses and
  // (RobustOptions::weights_ride_trial_sums) the weights of each update after an accepted Newton
  // step travel beside its trial's sums: fewer exchange steps than with a weight exchange per
  // outer step, as the DDS agents count too, for the same set.
  GncDistributedOptions own_weights = in_process_options();
  own_weights.robust.weights_ride_trial_sums = false;
  const GncDistributedResult apart = solve_gnc_distributed(g, dds.assignment, own_weights);
  EXPECT_GE(apart.exchange_steps, apart.outer_iterations + 2);
  EXPECT_LT(ref.exchange_steps, apart.exchange_steps);
  EXPECT_EQ(apart.rejected, ref.rejected);
  EXPECT_EQ(json_field(dds.summary, "gnc_exchange_steps"), ref.exchange_steps) << dds.summary;
  EXPECT_EQ(json_field(dds.summary, "message_steps_total"), message_steps(ref)) << dds.summary;
  EXPECT_EQ(json_field(dds.summary, "readmitted"), static_cast<double>(ref.readmitted));
  EXPECT_EQ(json_field(dds.summary, "outliers"), static_cast<double>(ref.rejected.size()));
  EXPECT_EQ(json_field(dds.summary, "inliers"),
            static_cast<double>(g.num_measurements() - ref.rejected.size()));
  EXPECT_EQ(json_array(dds.summary, "rejected"), ref.rejected) << dds.summary;
  EXPECT_EQ(lines_of(dds.dir + "/rejected.txt"), ref.rejected);
  // The cost over the kept measurements, rounded by the agents without a central step.
  EXPECT_NEAR(json_field(dds.summary, "cost"), ref.final_solve.cost, 1e-12 * ref.final_solve.cost)
      << dds.summary;
  EXPECT_NE(dds.summary.find("\"certified\": true"), std::string::npos) << dds.summary;
  EXPECT_NE(dds.summary.find("\"robust\": \"gnc-tls\""), std::string::npos) << dds.summary;
  EXPECT_EQ(json_field(dds.summary, "min_eigenvalue"), ref.final_solve.min_eigenvalue);

  // Every wrong closure found, nothing else, and no odometry edge (a known inlier) rejected.
  EXPECT_EQ(ref.rejected, dds.labels);
  for (std::size_t e : json_array(dds.summary, "rejected"))
    EXPECT_FALSE(is_known_inlier(g.measurements[e], KnownInliers::kOdometry)) << e;

  // The steps the DDS agents took matter here: with the wrong closures the vote takes the
  // known inliers' start, and without it and the kept set's fresh start the run differs (in its
  // rounds or, where GNC's weighted solves are Newton steps, in the refinements' message steps).
  GncDistributedOptions plain_start = in_process_options();
  plain_start.known_inlier_start = false;
  plain_start.kept_set_start = false;
  const GncDistributedResult other = solve_gnc_distributed(g, dds.assignment, plain_start);
  EXPECT_NE(std::make_pair(other.total_rounds, other.refine_message_steps),
            std::make_pair(ref.total_rounds, ref.refine_message_steps));
}

// Clean data: the start vote takes the solver's own (chordal) start, which is nearly the
// optimum, over the odometry chains; over DDS as in process (same rounds, same cost).
TEST(DdsRobust, OnCleanDataTheVoteTakesTheSolversStartAsInProcess) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 216 --robots 3 --seed 4");
  const std::string run = "robust-clean-" + std::to_string(getpid());
  const auto [summary, assignment] = robust_run(dir, graph, run, 70, "gnc-tls");
  const PoseGraph g = read_g2o(graph);
  const GncDistributedResult ref = solve_gnc_distributed(g, assignment, in_process_options());
  EXPECT_TRUE(ref.rejected.empty());
  EXPECT_EQ(json_field(summary, "rounds"), ref.total_rounds) << summary;
  EXPECT_EQ(json_field(summary, "outliers"), 0) << summary;
  EXPECT_NEAR(json_field(summary, "cost"), ref.final_solve.cost, 1e-12 * ref.final_solve.cost);
  EXPECT_NE(summary.find("\"certified\": true"), std::string::npos) << summary;
  // The vote's choice: the run from the solver's start alone takes the same rounds, the one
  // from the known inliers' start alone (the odometry chains) more. Both with the plain first
  // solve (RobustOptions::weigh_at_start off), which the run without a vote has.
  GncDistributedOptions voted = in_process_options();
  voted.robust.weigh_at_start = false;
  GncDistributedOptions solver_start = voted;
  solver_start.known_inlier_start = false;
  EXPECT_EQ(solve_gnc_distributed(g, assignment, solver_start).total_rounds,
            solve_gnc_distributed(g, assignment, voted).total_rounds);
}

// With --known-inliers none every measurement may go; the known inliers' start is then not
// available (odometry is not known), and the run still equals the in-process engine.
TEST(DdsRobust, WithoutKnownInliersTheRunStillEqualsTheInProcessEngine) {
  const RobustRun dds = robust_dds_run(43, {"--known-inliers", "none", "--init", "chordal"});
  const PoseGraph g = read_g2o(dds.graph);
  GncDistributedOptions o = in_process_options();
  o.robust.known_inliers = KnownInliers::kNone;
  const GncDistributedResult ref = solve_gnc_distributed(g, dds.assignment, o);
  expect_same_run(dds.summary, ref);
}

// The probes over DDS: on a soft map with group outliers a probe runs and stays (the in-process
// engine's GncDistributed.AProbeThatLowersTheTlsCostStaysAndFindsMoreOutliers), and the agents
// take the same steps as in process: the same probes, rounds, rejected set and cost.
TEST(DdsRobust, AProbeOverDdsEqualsTheInProcessEngine) {
  const std::string dir = temp_dir();
  const GeneratorResult city = flexible_city(0.1, OutlierKind::kGroup, 3);
  const std::string graph = dir + "/graph.g2o";
  write_g2o(city.graph, graph);
  const std::string run = "robust-probe-" + std::to_string(getpid());
  // From the solver's start alone (the coordinator's --gnc-solver-start, what `launch --init`
  // passes: no start vote, so the plain first solve runs; weighed at the voted start GNC alone
  // finds exactly the wrong closures here).
  const auto [summary, assignment] =
      robust_run(dir, graph, run, 137, "gnc-tls", {"--gnc-probes", "1", "--gnc-solver-start"});
  const PoseGraph g = read_g2o(graph);
  GncDistributedOptions o = in_process_options();
  o.known_inlier_start = false;
  o.robust.recheck_probes = 1;
  const GncDistributedResult ref = solve_gnc_distributed(g, assignment, o);
  ASSERT_EQ(ref.probes, 1);
  EXPECT_EQ(ref.probes_kept, 1);
  EXPECT_EQ(json_field(summary, "probes"), ref.probes) << summary;
  EXPECT_EQ(json_field(summary, "probes_kept"), ref.probes_kept) << summary;
  EXPECT_EQ(json_field(summary, "rounds"), ref.total_rounds) << summary;
  EXPECT_EQ(json_array(summary, "rejected"), ref.rejected) << summary;
  EXPECT_NEAR(json_field(summary, "cost"), ref.final_solve.cost, 1e-12 * ref.final_solve.cost);
  EXPECT_NE(summary.find("\"certified\": true"), std::string::npos) << summary;
}

// `tessera launch` end to end: the robust fields in the summary, and an input whose every
// measurement looks wrong ends with a message naming the cause instead of a collapsed graph.
TEST(DdsRobust, LaunchReportsTheRejectedSetAndRefusesAnAllOutlierInput) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o",
                     "--kind grid3d --poses 125 --robots 3 --seed 2 --outliers 0.25 "
                     "--labels " +
                         dir + "/labels.json");
  std::string out;
  int rc = run_command(bin("tessera") + " launch " + graph +
                           " --agents 3 --domain 44 --timeout 60 --robust gnc-tls --json " + dir +
                           "/s.json --rejected " + dir + "/rejected.txt 2>&1",
                       &out);
  ASSERT_EQ(rc, 0) << out;
  const std::string json = slurp(dir + "/s.json");
  const std::vector<std::size_t> labels = json_array(slurp(dir + "/labels.json"), "outliers");
  EXPECT_EQ(json_array(json, "rejected"), labels) << json;
  EXPECT_EQ(lines_of(dir + "/rejected.txt"), labels);
  EXPECT_GT(json_field(json, "outer_iterations"), 0) << json;
  EXPECT_NE(json.find("\"certified\": true"), std::string::npos) << json;

  rc = run_command(bin("tessera") + " launch " + graph +
                       " --agents 3 --domain 45 --timeout 60 --robust gnc-tls --known-inliers none "
                       "--inlier-threshold 1e-6 2>&1",
                   &out);
  EXPECT_NE(rc, 0) << out;
  EXPECT_NE(out.find("unconnected parts, so no estimate is defined"), std::string::npos) << out;

  // Bad options name the flag and the field before anything starts.
  rc = run_command(bin("tessera") + " launch " + graph + " --robust gnc-tls --gnc-mu-step 1 2>&1",
                   &out);
  EXPECT_EQ(rc, 2) << out;
  EXPECT_NE(out.find("--gnc-mu-step: RobustOptions.mu_step"), std::string::npos) << out;
}

// `tessera launch` on dpgo's measurement CSV: robot k of the file is agent k (its own g2o file
// written by launch), and the robust run equals the in-process engine on the same CSV.
TEST(DdsRobust, LaunchOnADpgoCsvFileEqualsTheInProcessEngine) {
  const std::string dir = temp_dir();
  const std::string graph = generate_graph(
      dir + "/graph.g2o", "--kind grid3d --poses 216 --robots 3 --seed 4 --outliers 0.25");
  const PoseGraph g = read_g2o(graph);
  std::ofstream(dir + "/measurements.csv") << dpgo_csv_of(g, 72);
  std::string out;
  const int rc = run_command(bin("tessera") + " launch " + dir +
                                 "/measurements.csv --agents 3 --partition sequential --domain 46 "
                                 "--timeout 60 --seed 7 --robust gnc-tls --json " +
                                 dir + "/s.json 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  const std::string json = slurp(dir + "/s.json");

  const DpgoCsvGraph read = read_dpgo_csv(dir + "/measurements.csv");
  const GncDistributedResult ref = solve_gnc_distributed(
      read.graph, std::vector<int>(read.robot_of.begin(), read.robot_of.end()),
      in_process_options());
  EXPECT_EQ(json_field(json, "poses"), 216);
  expect_same_run(json, ref);
  EXPECT_NE(json.find("\"certified\": true"), std::string::npos) << json;

  // One agent per robot of the file.
  EXPECT_NE(
      run_command(bin("tessera") + " launch " + dir + "/measurements.csv --agents 2 2>&1", &out),
      0);
  EXPECT_NE(out.find("holds 3 robots but --agents is 2"), std::string::npos) << out;
}

// A CSV's is_known_inlier flag reaches the DDS agents (robot file, announcement, assignment):
// a wrong inter-robot closure flagged as a known inlier is never rejected over DDS, the run
// equals the in-process engine given the same flags, and without the flag it is rejected.
TEST(DdsRobust, ACsvKnownInlierFlagIsNeverRejectedOverDds) {
  const std::string dir = temp_dir();
  const std::string graph = generate_graph(dir + "/graph.g2o",
                                           "--kind grid3d --poses 216 --robots 3 --seed 4 "
                                           "--outliers 0.25 --labels " +
                                               dir + "/labels.json");
  const PoseGraph g = read_g2o(graph);
  const std::vector<std::size_t> labels = json_array(slurp(dir + "/labels.json"), "outliers");
  std::size_t flagged = g.measurements.size();
  for (std::size_t e : labels)
    if (g.measurements[e].i / 72 != g.measurements[e].j / 72) {
      flagged = e;
      break;
    }
  ASSERT_LT(flagged, g.measurements.size()) << "an inter-robot wrong closure to flag";
  std::ofstream(dir + "/measurements.csv") << dpgo_csv_of(g, 72, {flagged});
  std::string out;
  const int rc = run_command(bin("tessera") + " launch " + dir +
                                 "/measurements.csv --agents 3 --partition sequential --domain 71 "
                                 "--timeout 60 --seed 7 --robust gnc-tls --json " +
                                 dir + "/s.json 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  const std::string json = slurp(dir + "/s.json");
  const std::vector<std::size_t> rejected = json_array(json, "rejected");
  EXPECT_EQ(std::count(rejected.begin(), rejected.end(), flagged), 0) << json;

  const DpgoCsvGraph read = read_dpgo_csv(dir + "/measurements.csv");
  const std::vector<int> robots(read.robot_of.begin(), read.robot_of.end());
  GncDistributedOptions o = in_process_options();
  o.known_inlier_flags = read.known_inlier;
  const GncDistributedResult ref = solve_gnc_distributed(read.graph, robots, o);
  EXPECT_EQ(rejected, ref.rejected) << json;
  EXPECT_EQ(json_field(json, "rounds"), ref.total_rounds) << json;
  EXPECT_NEAR(json_field(json, "cost"), ref.final_solve.cost, 1e-12 * ref.final_solve.cost);

  o.known_inlier_flags.clear();
  const GncDistributedResult unflagged = solve_gnc_distributed(read.graph, robots, o);
  EXPECT_EQ(std::count(unflagged.rejected.begin(), unflagged.rejected.end(), flagged), 1);
}

// --robust pcm-gnc over DDS: agent 0 runs the pairwise consistency check on the values the
// others send it, every agent starts GNC with the inconsistent closures at weight 0; the run
// equals the in-process engine and finds a group of mutually consistent wrong closures.
TEST(DdsRobust, PcmGncOverDdsEqualsTheInProcessEngine) {
  const std::string dir = temp_dir();
  const std::string graph = generate_graph(dir + "/graph.g2o",
                                           "--kind grid3d --poses 216 --robots 3 --seed 4 "
                                           "--outliers 0.1 --outlier-kind group --labels " +
                                               dir + "/labels.json");
  const std::string run = "robust-pcm-" + std::to_string(getpid());
  const auto [summary, assignment] = robust_run(dir, graph, run, 72, "pcm-gnc");
  const PoseGraph g = read_g2o(graph);
  GncDistributedOptions o = in_process_options();
  o.robust.kind = RobustKind::kPcmGnc;
  const GncDistributedResult ref = solve_gnc_distributed(g, assignment, o);
  EXPECT_NE(summary.find("\"robust\": \"pcm-gnc\""), std::string::npos) << summary;
  expect_same_run(summary, ref);
  EXPECT_NE(summary.find("\"certified\": true"), std::string::npos) << summary;
  EXPECT_EQ(ref.rejected, json_array(slurp(dir + "/labels.json"), "outliers"));
}

// Cluster probes (--gnc-cluster-probes) over DDS: every agent process runs the same search on the
// same data, so the probes, rounds, rejected set and cost equal the in-process engine's.
TEST(DdsRobust, ClusterProbesOverDdsEqualTheInProcessEngine) {
  const std::string dir = temp_dir();
  const GeneratorResult city = flexible_city(0.1, OutlierKind::kGroup, 3);
  const std::string graph = dir + "/graph.g2o";
  write_g2o(city.graph, graph);
  const std::string run = "robust-cluster-" + std::to_string(getpid());
  // From the solver's start alone, as in AProbeOverDdsEqualsTheInProcessEngine.
  const auto [summary, assignment] = robust_run(
      dir, graph, run, 229, "gnc-tls", {"--gnc-cluster-probes", "20", "--gnc-solver-start"});
  const PoseGraph g = read_g2o(graph);
  GncDistributedOptions o = in_process_options();
  o.known_inlier_start = false;
  o.cluster_probes = 20;
  const GncDistributedResult ref = solve_gnc_distributed(g, assignment, o);
  // Beyond the agents' tail probes: the cluster search ran.
  ASSERT_GT(ref.probes, RobustOptions{}.recheck_probes);
  EXPECT_GE(ref.probes_kept, 1);
  EXPECT_EQ(json_field(summary, "probes"), ref.probes) << summary;
  EXPECT_EQ(json_field(summary, "probes_kept"), ref.probes_kept) << summary;
  expect_same_run(summary, ref);
  EXPECT_EQ(json_field(summary, "min_eigenvalue"), ref.final_solve.min_eigenvalue);
  EXPECT_NE(summary.find("\"certified\": true"), std::string::npos) << summary;
}

// --gnc-pass-refine auto and --gnc-mu-step-max reach the agent processes through the
// assignment: the inlier passes end with the Newton refinement and mu takes the adaptive steps
// over DDS as in process, with the same outer steps, rounds, refinement message steps, rejected
// set and cost.
TEST(DdsRobust, PassRefineOverDdsEqualsTheInProcessEngine) {
  const RobustRun dds =
      robust_dds_run(188, {"--gnc-pass-refine", "auto", "--gnc-mu-step-max", "4"});
  const PoseGraph g = read_g2o(dds.graph);
  GncDistributedOptions o = in_process_options();
  o.robust.refine_passes = true;
  o.robust.mu_step_max = 4;
  const GncDistributedResult ref = solve_gnc_distributed(g, dds.assignment, o);
  ASSERT_GT(ref.refine_message_steps, 0) << "the passes should hand over to the refinement";
  GncDistributedOptions fixed = o;
  fixed.robust.mu_step_max = 0;
  fixed.robust.newton_mu_step_max = 0;
  ASSERT_LT(ref.outer_iterations, solve_gnc_distributed(g, dds.assignment, fixed).outer_iterations)
      << "the adaptive steps should shorten the schedule (15 against 24 outer steps)";
  EXPECT_EQ(json_field(dds.summary, "gnc_refine_steps"), ref.refine_message_steps) << dds.summary;
  expect_same_run(dds.summary, ref);
  EXPECT_EQ(ref.rejected, dds.labels);
  EXPECT_NE(dds.summary.find("\"certified\": true"), std::string::npos) << dds.summary;
}

// RobustOptions::jump_band (on by default, no flag: every agent runs with the default): the
// count of residuals near the bound rides in the weights exchange, and over DDS the early end
// comes at the same outer step with the same set, rounds and cost as in process.
TEST(DdsRobust, TheEarlyEndOverDdsEqualsTheInProcessEngine) {
  const RobustRun dds = robust_dds_run(119);
  const PoseGraph g = read_g2o(dds.graph);
  const GncDistributedOptions o = in_process_options();
  const GncDistributedResult ref = solve_gnc_distributed(g, dds.assignment, o);
  GncDistributedOptions full = o;
  full.robust.jump_band = 0;
  ASSERT_LT(ref.outer_iterations, solve_gnc_distributed(g, dds.assignment, full).outer_iterations)
      << "the residuals should leave the bound's band before the weights are binary";
  expect_same_run(dds.summary, ref);
  EXPECT_EQ(ref.rejected, dds.labels);
  EXPECT_NE(dds.summary.find("\"certified\": true"), std::string::npos) << dds.summary;
}

}  // namespace
}  // namespace tessera::test::dds
