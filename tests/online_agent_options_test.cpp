// `tessera-agent --online`'s options (agent/online_agent_options.hpp): the local rounds and the
// factor growth that `tessera solve --online` takes reach the agent's OnlineOptions, with the
// same defaults and checks, and its usage text lists them.

#include "agent/online_agent_options.hpp"

#include <gtest/gtest.h>

#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera::agent {
namespace {

using Argv = std::vector<std::string>;

OnlineAgentOptions parsed(Argv extra) {
  Argv argv = {"--online", "--robots", "3", "--id", "1", "--run-id", "r1"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return parse_online_agent_options(argv);
}

TEST(OnlineAgentOptions, LocalRoundsAreOnAndBlocksFactorAgainWhenTheyGrowByDefault) {
  const OnlineAgentOptions o = parsed({});
  EXPECT_TRUE(o.online.solver.local_rounds.enabled);
  EXPECT_EQ(o.online.solver.local_rounds.threshold, 1.0);
  EXPECT_EQ(o.online.refactor_growth, 0.0);
}

TEST(OnlineAgentOptions, TakeTheFactorGrowthAndLocalRoundsOfSolveOnline) {
  const OnlineAgentOptions threshold = parsed({"--local-threshold", "0.5"});
  EXPECT_TRUE(threshold.online.solver.local_rounds.enabled);
  EXPECT_EQ(threshold.online.solver.local_rounds.threshold, 0.5);
  const OnlineAgentOptions off = parsed({"--no-local-rounds", "--refactor-growth", "0.25"});
  EXPECT_FALSE(off.online.solver.local_rounds.enabled);
  EXPECT_EQ(off.online.refactor_growth, 0.25);
}

TEST(OnlineAgentOptions, ABadGrowthOrThresholdIsNamed) {
  const auto error = [](const Argv& extra) { return test::input_error_of([&] { parsed(extra); }); };
  EXPECT_EQ(error({"--local-threshold", "2"}), "option --local-threshold: must be in (0, 1]");
  EXPECT_EQ(error({"--refactor-growth", "-1"}),
            "option --refactor-growth: must be a finite number >= 0");
}

TEST(OnlineAgentOptions, TheUsageListsTheFactorGrowthAndLocalRoundsWithTheirDefaults) {
  const std::string usage = online_agent_usage();
  EXPECT_NE(usage.find("  --refactor-growth G "), std::string::npos) << usage;
  EXPECT_NE(usage.find("  --local-threshold F "), std::string::npos) << usage;
  EXPECT_NE(usage.find("  --no-local-rounds "), std::string::npos) << usage;
  EXPECT_EQ(usage.find('%'), std::string::npos) << usage;  // every mark replaced
}

}  // namespace
}  // namespace tessera::agent
