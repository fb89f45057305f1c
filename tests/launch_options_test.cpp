// `tessera launch`'s options (launch/launch_options.hpp) and the command lines built from them
// (launch/launch_argv.hpp), without starting any process: forwarded flags reach the processes
// they are meant for, bad values are named, removed flags are refused, and the public
// dds::LaunchOptions say the same as the command line.

#include "launch/launch_options.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <tessera/dds/launch.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "launch/forwarded_flags.hpp"
#include "launch/launch_argv.hpp"
#include "launch/online_launch.hpp"
#include "launch/solve_only_flags.hpp"
#include "test_support.hpp"

namespace tessera::launch {
namespace {

using Argv = std::vector<std::string>;

bool has_pair(const Argv& argv, const std::string& flag, const std::string& value) {
  for (std::size_t k = 0; k + 1 < argv.size(); ++k)
    if (argv[k] == flag && argv[k + 1] == value) return true;
  return false;
}

bool has(const Argv& argv, const std::string& flag) {
  return std::find(argv.begin(), argv.end(), flag) != argv.end();
}

std::string error_of(const Argv& argv) {
  try {
    parse_launch_options(argv);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

RunPaths paths() {
  return {"/opt/tessera/bin", "/tmp/run", "/data/graph.g2o", "/tmp/run/summary.json"};
}

TEST(LaunchOptions, ForwardedFlagsReachOnlyTheCoordinatorWithTheirValues) {
  LaunchOptions o = parse_launch_options(
      {"--agents", "2", "--out", "merged.g2o", "--status-interval", "0.5", "--run-id", "r1"});
  o.graph = "/data/graph.g2o";
  const Argv coordinator = coordinator_argv(o, paths());
  EXPECT_TRUE(has_pair(coordinator, "--output", "merged.g2o"));  // renamed for the coordinator
  EXPECT_TRUE(has_pair(coordinator, "--status-interval", "0.5"));
  EXPECT_TRUE(has_pair(coordinator, "--run-id", "r1"));
  EXPECT_FALSE(has(coordinator, "--progress-interval"));  // not given: not forwarded
  const Argv agent = agent_argv(o, paths(), 1);
  EXPECT_FALSE(has(agent, "--output"));
  EXPECT_FALSE(has(agent, "--status-interval"));
  EXPECT_TRUE(has_pair(agent, "--id", "1"));
  EXPECT_TRUE(has_pair(agent, "--run-id", "r1"));
}

TEST(LaunchOptions, SetUpTimeoutReachesEveryProcessAsItsWaitBound) {
  LaunchOptions o = parse_launch_options({"--agents", "2", "--setup-timeout", "300"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--timeout", "300"));
  EXPECT_TRUE(has_pair(agent_argv(o, paths(), 0), "--timeout", "300"));
  EXPECT_TRUE(has_pair(agent_argv(o, paths(), 1), "--timeout", "300"));
  const LaunchOptions plain = parse_launch_options({"--agents", "2"});
  EXPECT_FALSE(has(agent_argv(plain, paths(), 0), "--timeout"));  // the processes' own 30 s
  EXPECT_NE(error_of({"--setup-timeout", "0"}).find("--setup-timeout"), std::string::npos);
}

TEST(LaunchOptions, AgentZeroSolvesTheChordalStartEarlyOnlyFromTheForkServersWholeFile) {
  LaunchOptions o = parse_launch_options({"--agents", "3"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has(agent_argv(o, paths(), 0), "--early-chordal"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 1), "--early-chordal"));  // only agent 0 solves it
  EXPECT_FALSE(has(coordinator_argv(o, paths()), "--early-chordal"));
  LaunchOptions distributed = parse_launch_options({"--agents", "3", "--init", "distributed"});
  distributed.graph = o.graph;
  EXPECT_FALSE(has(agent_argv(distributed, paths(), 0), "--early-chordal"));
  LaunchOptions exec = parse_launch_options({"--agents", "3", "--no-fork-server"});
  exec.graph = o.graph;  // no parsed file to solve from
  EXPECT_FALSE(has(agent_argv(exec, paths(), 0), "--early-chordal"));
}

TEST(LaunchOptions, EveryForwardedFlagIsAcceptedAndListedInTheHelp) {
  const std::string help = launch_help();
  // A valid value of each flag: "1" unless that is out of the flag's range.
  const std::map<std::string, std::string> value = {{"robust", "gnc-tls"},
                                                    {"known-inliers", "odometry"},
                                                    {"gnc-mu-step", "1.4"},
                                                    {"inlier-quantile", "0.5"},
                                                    {"refine", "newton"},
                                                    {"coarse-space", "smoothed"},
                                                    {"gnc-probe-ratio", "5"},
                                                    {"gnc-final-refine", "none"},
                                                    {"gnc-pass-refine", "auto"},
                                                    {"gnc-mu-step-max", "2"},
                                                    {"refine-sigma", "one"},
                                                    {"partition-nice", "-5"},
                                                    {"gnc-newton-mu-step-max", "4"},
                                                    {"gnc-mu-hold", "crossings"},
                                                    {"gnc-jump-side", "both"},
                                                    {"gnc-probe-cut", "always"},
                                                    {"gnc-step-sigma", "every"},
                                                    {"tangent-dots", "sequential"}};
  for (const ForwardedFlag& f : forwarded_flags()) {
    EXPECT_NE(help.find(std::string("--") + f.name), std::string::npos) << f.name;
    Argv argv = {std::string("--") + f.name};
    if (f.valued) argv.push_back(value.count(f.name) ? value.at(f.name) : "1");
    EXPECT_EQ(error_of(argv), "") << f.name;
  }
}

TEST(LaunchOptions, BadValuesAreNamedAndRemovedFlagsRefused) {
  EXPECT_NE(error_of({"--agents", "0"}).find("--agents"), std::string::npos);
  EXPECT_NE(error_of({"--status-interval", "-1"}).find("--status-interval"), std::string::npos);
  EXPECT_NE(error_of({"--progress-interval", "x"}).find("--progress-interval"), std::string::npos);
  EXPECT_NE(error_of({"--partition-time", "-2"}).find("--partition-time"), std::string::npos);
  EXPECT_NE(error_of({"--certify", "--no-certify"}).find("exclude"), std::string::npos);
  EXPECT_NE(error_of({"--agents-yield"}).find("--agents-yield"), std::string::npos);
  EXPECT_EQ(launch_help().find("agents-yield"), std::string::npos);
}

TEST(LaunchOptions, CoarseSpaceFlagsReachTheCoordinatorOnly) {
  LaunchOptions o = parse_launch_options({"--coarse-every", "1", "--coarse-space", "smoothed",
                                          "--coarse-aggregates", "8", "--coarse-smoothing", "2"});
  o.graph = "/data/graph.g2o";
  const Argv coordinator = coordinator_argv(o, paths());
  EXPECT_TRUE(has_pair(coordinator, "--coarse-every", "1"));
  EXPECT_TRUE(has_pair(coordinator, "--coarse-space", "smoothed"));
  EXPECT_TRUE(has_pair(coordinator, "--coarse-aggregates", "8"));
  EXPECT_TRUE(has_pair(coordinator, "--coarse-smoothing", "2"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--coarse-space"));
  EXPECT_NE(error_of({"--coarse-space", "rigid"}).find("--coarse-space"), std::string::npos);
  EXPECT_NE(error_of({"--coarse-smoothing", "9"}).find("--coarse-smoothing"), std::string::npos);
  EXPECT_NE(error_of({"--coarse-aggregates", "0"}).find("--coarse-aggregates"), std::string::npos);
  EXPECT_NE(error_of({"--coarse-every", "x"}).find("--coarse-every"), std::string::npos);
}

TEST(LaunchOptions, ReferenceCostReachesTheCoordinatorOnlyAndMustBePositive) {
  LaunchOptions o = parse_launch_options({"--reference-cost", "6055513.25"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--reference-cost", "6055513.25"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--reference-cost"));
  for (const char* bad : {"0", "-3", "x", "inf"})
    EXPECT_NE(error_of({"--reference-cost", bad}).find("--reference-cost"), std::string::npos)
        << bad;
}

TEST(LaunchOptions, ProbeAndFinalRefineFlagsReachTheCoordinatorAndNameBadValues) {
  LaunchOptions o = parse_launch_options({"--robust", "gnc-tls", "--gnc-probes", "3",
                                          "--gnc-probe-ratio", "8", "--gnc-final-refine", "none"});
  o.graph = "/data/graph.g2o";
  const Argv coordinator = coordinator_argv(o, paths());
  EXPECT_TRUE(has_pair(coordinator, "--gnc-probes", "3"));
  EXPECT_TRUE(has_pair(coordinator, "--gnc-probe-ratio", "8"));
  EXPECT_TRUE(has_pair(coordinator, "--gnc-final-refine", "none"));
  const std::string ratio = error_of({"--gnc-probe-ratio", "1"});
  EXPECT_NE(ratio.find("--gnc-probe-ratio"), std::string::npos) << ratio;
  EXPECT_NE(ratio.find("probe_ratio"), std::string::npos) << ratio;
  const std::string probes = error_of({"--gnc-probes", "-1"});
  EXPECT_NE(probes.find("--gnc-probes"), std::string::npos) << probes;
  EXPECT_NE(probes.find("recheck_probes"), std::string::npos) << probes;
  EXPECT_NE(error_of({"--gnc-final-refine", "lbfgs"}).find("--gnc-final-refine"),
            std::string::npos);
}

TEST(LaunchOptions, TuningFlagsSitUnderTheAdvancedHeading) {
  const std::string help = launch_help();
  const std::size_t advanced = help.find("advanced");
  ASSERT_NE(advanced, std::string::npos);
  for (const char* flag : {"--no-fork-server", "--no-agents-batch", "--no-status-relay"})
    EXPECT_GT(help.find(flag), advanced) << flag;
}

// launch partitions with auto by default (fast or eco by the graph's size, a small share of the
// run, docs/partitioning.md) and hands --partition-time to the coordinator only.
TEST(LaunchOptions, DefaultPresetIsAutoAndThePartitionTimeReachesTheCoordinator) {
  LaunchOptions o = parse_launch_options({"--partition-time", "2.5"});
  EXPECT_EQ(o.partition, "auto");
  const Argv coordinator = coordinator_argv(o, paths());
  EXPECT_TRUE(has_pair(coordinator, "--partition", "auto"));
  EXPECT_TRUE(has_pair(coordinator, "--partition-time", "2.5"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--partition-time"));
}

// The early partition thread's nice (coordinator/partition_priority.hpp) is the coordinator's
// business alone; a raise above the run's priority is the only thing it may ask for.
TEST(LaunchOptions, PartitionNiceReachesTheCoordinatorOnlyAndStaysInMinus20To0) {
  LaunchOptions o = parse_launch_options({"--partition-nice", "-20"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--partition-nice", "-20"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--partition-nice"));
  for (const char* bad : {"1", "-21", "-2.5", "x"})
    EXPECT_NE(error_of({"--partition-nice", bad}).find("--partition-nice"), std::string::npos)
        << bad;
}

TEST(LaunchOptions, GradientToleranceReachesTheCoordinatorAsTheSameNumber) {
  for (const char* text : {"0.01", "1e-7", "0.1", "0.3333333333333333"}) {
    const LaunchOptions o = parse_launch_options({"--grad-tol", text});
    const Argv coordinator = coordinator_argv(o, paths());
    const auto at = std::find(coordinator.begin(), coordinator.end(), "--grad-tol");
    ASSERT_NE(at, coordinator.end());
    EXPECT_EQ(std::stod(*(at + 1)), std::stod(text)) << *(at + 1);
  }
}

TEST(LaunchOptions, PublicOptionsParseToTheSameRun) {
  dds::LaunchOptions pub;
  pub.agents = 4;
  pub.algorithm = "rbcd++";
  pub.partition = "eco";
  pub.grad_tol = 1e-3;
  pub.certify = false;
  pub.out = "x.g2o";
  pub.session.run_id = "public-run";
  pub.session.domain = 12;
  pub.extra_args = {"--progress-interval", "0"};
  const LaunchOptions o = parse_launch_options(pub.argv());
  EXPECT_EQ(o.agents, 4);
  EXPECT_EQ(o.algorithm, "rbcd++");
  EXPECT_EQ(o.partition, "eco");
  EXPECT_EQ(o.grad_tol, 1e-3);
  EXPECT_FALSE(o.certify);
  EXPECT_EQ(o.net.session.run_id, "public-run");
  EXPECT_EQ(o.net.session.domain, 12);
  const Argv coordinator = coordinator_argv(o, paths());
  EXPECT_TRUE(has_pair(coordinator, "--output", "x.g2o"));
  EXPECT_TRUE(has_pair(coordinator, "--progress-interval", "0"));
  pub.agents = 65;
  EXPECT_TRUE(test::validation_names(pub, "--agents"));
}

TEST(LaunchOptions, ClusterProbesReachTheCoordinatorAndABadCountNamesTheFlag) {
  LaunchOptions o = parse_launch_options({"--robust", "gnc-tls", "--gnc-cluster-probes", "20"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--gnc-cluster-probes", "20"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--gnc-cluster-probes"));
  for (const char* bad : {"-1", "2.5", "x"}) {
    const std::string e = error_of({"--gnc-cluster-probes", bad});
    EXPECT_NE(e.find("--gnc-cluster-probes"), std::string::npos) << bad << ": " << e;
  }
}

TEST(LaunchOptions, PassRefineReachesTheCoordinatorAndABadValueNamesTheFlag) {
  LaunchOptions o = parse_launch_options({"--robust", "gnc-tls", "--gnc-pass-refine", "auto"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--gnc-pass-refine", "auto"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--gnc-pass-refine"));
  const std::string e = error_of({"--gnc-pass-refine", "newton"});
  EXPECT_NE(e.find("--gnc-pass-refine"), std::string::npos) << e;
}

}  // namespace
}  // namespace tessera::launch

namespace tessera::launch {
namespace {

TEST(LaunchOptions, RefineSigmaReachesTheCoordinatorAndABadValueNamesTheFlag) {
  LaunchOptions o = parse_launch_options({"--refine-sigma", "one"});
  o.graph = "/data/graph.g2o";
  EXPECT_TRUE(has_pair(coordinator_argv(o, paths()), "--refine-sigma", "one"));
  EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--refine-sigma"));  // the assignment carries it
  const std::string e = error_of({"--refine-sigma", "all"});
  EXPECT_NE(e.find("--refine-sigma"), std::string::npos) << e;
}

}  // namespace
}  // namespace tessera::launch

namespace tessera::launch {
namespace {

// The options that were `tessera solve`'s only: launch passes them to the coordinator, which
// puts them in the assignment (transport/assignment_options.hpp), so no agent gets them on its
// command line; bad values are named before any process starts.
TEST(LaunchOptions, SolveOnlyGncAndTangentFlagsReachTheCoordinatorAndNameBadValues) {
  const std::vector<std::pair<std::string, std::string>> flags = {
      {"gnc-mu-hold", "crossings"}, {"gnc-step-trust", "0.5"},     {"gnc-newton-mu-step-max", "9"},
      {"gnc-jump-side", "both"},    {"gnc-probe-cut", "always"},   {"gnc-step-sigma", "every"},
      {"gnc-jump-band-max", "12"},  {"tangent-dots", "sequential"}};
  Argv argv = {"--robust", "gnc-tls"};
  for (const auto& [flag, value] : flags) argv.insert(argv.end(), {"--" + flag, value});
  LaunchOptions o = parse_launch_options(argv);
  o.graph = "/data/graph.g2o";
  const Argv coordinator = coordinator_argv(o, paths());
  for (const auto& [flag, value] : flags) {
    EXPECT_TRUE(has_pair(coordinator, "--" + flag, value)) << flag;
    EXPECT_FALSE(has(agent_argv(o, paths(), 0), "--" + flag)) << flag;
  }
  const std::map<std::string, std::string> bad = {
      {"gnc-mu-hold", "rises"},    {"gnc-step-trust", "1.5"},   {"gnc-newton-mu-step-max", "1"},
      {"gnc-jump-side", "inside"}, {"gnc-probe-cut", "never"},  {"gnc-step-sigma", "one"},
      {"gnc-jump-band-max", "-1"}, {"tangent-dots", "parallel"}};
  for (const auto& [flag, value] : bad) {
    const std::string e = error_of({"--" + flag, value});
    EXPECT_NE(e.find("--" + flag), std::string::npos) << flag << ": " << e;
  }
}

// A `tessera solve` option that cannot reach the agent processes is refused by name, with the
// reason, instead of as an unknown option.
TEST(LaunchOptions, SolveOnlyFlagsAreRefusedWithTheirReason) {
  const std::string select = error_of({"--agents", "3", "--select", "uniform"});
  EXPECT_NE(select.find("--select is an option of `tessera solve` only"), std::string::npos)
      << select;
  EXPECT_NE(select.find("assignment does not carry it"), std::string::npos) << select;
  const std::string reference = error_of({"--reference"});
  EXPECT_NE(reference.find("--reference-cost"), std::string::npos) << reference;
  const std::string stop = error_of({"--stop=gradient"});
  EXPECT_NE(stop.find("centralized"), std::string::npos) << stop;
  EXPECT_NE(error_of({"--sequential"}).find("--sequential is an option"), std::string::npos);
  // No row names a flag launch takes.
  const std::string help = launch_help();
  for (const SolveOnlyFlag& f : solve_only_flags()) {
    EXPECT_EQ(find_forwarded_flag(f.name), nullptr) << f.name;
    EXPECT_EQ(help.find(std::string("  --") + f.name + " "), std::string::npos) << f.name;
  }
}

// An online launch takes `tessera solve --online`'s factor growth and local rounds (it passes
// them to every agent), names a bad value before it starts anything, and lists them in its
// help; the flags a run over DDS cannot use are still refused.
TEST(LaunchOptions, AnOnlineLaunchTakesTheFactorGrowthAndLocalRounds) {
  const std::vector<std::string> flags = {"refactor-growth", "local-threshold", "no-local-rounds"};
  EXPECT_NO_THROW(refuse_solve_only_flags(
      {"--refactor-growth", "0.1", "--local-threshold=0.5", "--no-local-rounds"},
      online_solve_only_flags()));
  EXPECT_THROW(refuse_solve_only_flags({"--checkpoints", "3"}, online_solve_only_flags()),
               InputError);
  const std::string graph = test::write_file(test::temp_dir(), "graph.g2o", "");
  const auto error = [&graph](const Argv& extra) {
    Argv argv = {graph, "--agents", "3", "--online"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return test::input_error_of([&argv] { run_online_launch(argv); });
  };
  EXPECT_EQ(error({"--local-threshold", "0"}), "option --local-threshold: must be in (0, 1]");
  EXPECT_EQ(error({"--no-local-rounds", "--refactor-growth", "-1"}),
            "option --refactor-growth: must be a finite number >= 0");
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run_online_launch({"--online", "--help"}), 0);
  const std::string help = ::testing::internal::GetCapturedStdout();
  for (const std::string& f : flags)
    EXPECT_NE(help.find("  --" + f + " "), std::string::npos) << f << "\n" << help;
  for (const SolveOnlyFlag& f : online_solve_only_flags())
    EXPECT_EQ(help.find(std::string("  --") + f.name + " "), std::string::npos) << f.name;
}

}  // namespace
}  // namespace tessera::launch
