// Solver options that were `tessera solve`'s only, now carried to the agent processes
// (transport/assignment_options.hpp for a batch run, the online agents' team options for an
// online one): a launch with a non-default value gives the in-process solve's run with that
// value, and an online agent with another value than the lead's is refused. Domains 109, 122,
// 123, 133 and 212.

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

// A JSON array of integers of a flat summary ("rejected").
std::string json_array_text(const std::string& json, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + name + "\": \\[([^\\]]*)\\]"))) return "?";
  return m[1].str();
}

// `tessera launch GRAPH ARGS --json DIR/NAME.json` (exit code 0, a test failure otherwise): the
// summary's text.
std::string launch_summary(const std::string& dir, const std::string& graph,
                           const std::string& args, const std::string& name) {
  const std::string json = dir + "/" + name + ".json";
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph + " " + args +
                            " --timeout 300 --json " + json + " 2>&1",
                        &out),
            0)
      << out;
  return read_text_file(json);
}

// The same robust run: outer steps, rounds, message steps, rejected set and cost.
void expect_same_robust_run(const std::string& launch, const std::string& solve) {
  for (const char* key : {"outer_iterations", "total_rounds", "message_steps_total", "probes"})
    EXPECT_EQ(json_text(launch, key), json_text(solve, key)) << key << "\n" << launch << solve;
  EXPECT_EQ(json_array_text(launch, "rejected"), json_array_text(solve, "rejected"));
  const double f = json_number(solve, "cost");
  EXPECT_NEAR(json_number(launch, "cost"), f, 1e-9 * f);
  EXPECT_EQ(json_text(launch, "certified"), "true") << launch;
}

// The GNC flags that were `tessera solve`'s only reach every agent over DDS: a launch with them
// runs what the in-process solve runs with them, which is not what either runs without them.
TEST(DdsForwardedOptions, ALaunchWithTheGncFlagsRunsTheSolvesRun) {
  const std::string dir = temp_dir();
  const std::string graph = generate_graph(
      dir + "/graph.g2o", "--kind grid3d --poses 216 --robots 3 --seed 4 --outliers 0.25");
  const std::string common = "--agents 3 --partition sequential --robust gnc-tls";
  const std::string flags =
      " --gnc-mu-hold crossings --gnc-step-trust 0 --gnc-newton-mu-step-max 0"
      " --gnc-jump-side both --gnc-jump-band-max 12 --gnc-probe-cut always --gnc-step-sigma every";
  const std::string solve_args = common + " --algorithm irbcd --certify";
  const std::string solve = solve_summary(dir, graph, solve_args + flags, "solve");
  const std::string plain = solve_summary(dir, graph, solve_args, "plain");
  // The flags change the in-process run.
  EXPECT_NE(json_text(solve, "message_steps_total"), json_text(plain, "message_steps_total"));
  EXPECT_EQ(json_text(solve, "gnc_mu_hold"), "\"crossings\"");
  const std::string launch = launch_summary(dir, graph, common + " --domain 109" + flags, "launch");
  ASSERT_FALSE(::testing::Test::HasFailure());
  expect_same_robust_run(launch, solve);
}

// --tangent-dots sequential reaches every agent: the launch's rounds end at the in-process
// solve's iterate to the last bit (the same gradient norm, printed to 17 digits), as with the
// default split sums, and the two sums end at different iterates. (The written poses differ in
// the last digits either way: the distributed rounding is not the direct one.)
TEST(DdsForwardedOptions, ALaunchWithSequentialTangentDotsEndsAtTheSolvesIterate) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 240 --robots 3 --seed 5");
  const std::string common = " --agents 3 --partition eco --no-certify --tangent-dots ";
  std::map<std::string, std::string> grad;
  for (const std::string dots : {"sequential", "split"}) {
    const std::string solve =
        solve_summary(dir, graph, "--algorithm irbcd" + common + dots, dots + "-solve");
    const std::string launch =
        launch_summary(dir, graph, "--domain 122" + common + dots, dots + "-launch");
    ASSERT_FALSE(::testing::Test::HasFailure());
    EXPECT_EQ(json_text(launch, "rounds"), json_text(solve, "rounds")) << dots;
    EXPECT_EQ(json_text(launch, "grad_norm"), json_text(solve, "grad_norm")) << dots;
    const double f = json_number(solve, "cost");
    EXPECT_NEAR(json_number(launch, "cost"), f, 1e-12 * f) << dots;
    grad[dots] = json_text(solve, "grad_norm");
  }
  EXPECT_NE(grad["sequential"], grad["split"]);
}

// Online: launch passes --first-step-factors, --tangent-dots and --local-threshold to every
// agent, which all use them, and the run ends where the in-process one does.
TEST(DdsForwardedOptions, AnOnlineLaunchPassesTheStepFactorsAndDotsToEveryAgent) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const std::string flags =
      " --rate 20 --speedup 2 --first-step-factors grown --tangent-dots sequential"
      " --local-threshold 0.5";
  const std::string in_process =
      solve_summary(dir, graph, "--online --robots 3 --no-progress" + flags, "in_process");
  EXPECT_EQ(json_text(in_process, "certified"), "true");
  const double f_in_process = json_number(in_process, "cost");
  const std::string json = online_launch(dir, graph, 123, flags);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_in_process, 1e-6 * f_in_process);
  for (int a = 0; a < 3; ++a) {
    const std::string agent = online_agent_summary(dir, a);
    EXPECT_EQ(json_text(agent, "first_step_factors"), "\"grown\"") << "agent " << a;
    EXPECT_EQ(json_text(agent, "tangent_dots"), "\"sequential\"") << "agent " << a;
    EXPECT_EQ(json_text(agent, "local_rounds"), "true") << "agent " << a;
    EXPECT_EQ(json_number(agent, "local_threshold"), 0.5) << "agent " << a;
    EXPECT_EQ(json_number(agent, "refactor_growth"), 0.0) << "agent " << a;
  }
  // Bad values and the in-process evaluation's flags are launch's own input errors.
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --first-step-factors old 2>&1",
                        &out),
            2);
  EXPECT_TRUE(contains(out, "option --first-step-factors: 'old'")) << out;
  EXPECT_EQ(
      run_command(bin("tessera") + " launch " + graph + " --agents 3 --online --checkpoints 3 2>&1",
                  &out),
      2);
  EXPECT_TRUE(contains(out, "--checkpoints is an option of `tessera solve` only")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --local-threshold 1.5 2>&1",
                        &out),
            2);
  EXPECT_TRUE(contains(out, "option --local-threshold: must be in (0, 1]")) << out;
}

// Online: launch passes --refactor-growth and --no-local-rounds to every agent (with the
// default first-step factors, so the growth decides when the grown blocks factor again), and
// the run ends where the in-process one does.
TEST(DdsForwardedOptions, AnOnlineLaunchPassesTheFactorGrowthAndNoLocalRoundsToEveryAgent) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const std::string flags = " --rate 20 --speedup 2 --refactor-growth 0.1 --no-local-rounds";
  const std::string in_process =
      solve_summary(dir, graph, "--online --robots 3 --no-progress" + flags, "in_process");
  EXPECT_EQ(json_text(in_process, "certified"), "true");
  const double f_in_process = json_number(in_process, "cost");
  const std::string json = online_launch(dir, graph, 212, flags);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_in_process, 1e-6 * f_in_process);
  for (int a = 0; a < 3; ++a) {
    const std::string agent = online_agent_summary(dir, a);
    EXPECT_EQ(json_number(agent, "refactor_growth"), 0.1) << "agent " << a;
    EXPECT_EQ(json_text(agent, "local_rounds"), "false") << "agent " << a;
    EXPECT_EQ(json_text(agent, "first_step_factors"), "\"new\"") << "agent " << a;
  }
}

TEST(DdsForwardedOptions, AnOnlineAgentWithOtherSolverOptionsThanTheLeadsIsRefused) {
  const std::string dir = temp_dir();
  const Process other =
      refused_beside_lead(dir, "online-factors-differ", 133, {"--first-step-factors", "grown"});
  EXPECT_TRUE(contains(other.output(),
                       "option --first-step-factors: this agent's new differs from the "
                       "lead's (agent 0) grown"))
      << other.output();
  const Process dots =
      refused_beside_lead(dir, "online-dots-differ", 133, {}, {"--tangent-dots", "sequential"});
  EXPECT_TRUE(contains(dots.output(),
                       "option --tangent-dots: this agent's sequential differs from the "
                       "lead's (agent 0) split"))
      << dots.output();
  // Local rounds decide which agents send their statuses each round.
  const Process local =
      refused_beside_lead(dir, "online-local-differs", 133, {"--no-local-rounds"});
  EXPECT_TRUE(contains(local.output(),
                       "option --no-local-rounds: this agent's absent differs from the "
                       "lead's (agent 0) given"))
      << local.output();
  const Process growth =
      refused_beside_lead(dir, "online-growth-differs", 133, {}, {"--refactor-growth", "0.25"});
  EXPECT_TRUE(contains(growth.output(),
                       "option --refactor-growth: this agent's 0.25 differs from the "
                       "lead's (agent 0) 0"))
      << growth.output();
}

}  // namespace
}  // namespace tessera::test::dds
