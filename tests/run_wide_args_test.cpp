// The solver options every online agent of a DDS run shares with the lead (cli/run_wide_args.hpp):
// `tessera solve --online`, `tessera launch --online` and `tessera-agent --online` read
// --refactor-growth, --local-threshold and --no-local-rounds with one parser, and an agent
// whose values differ from the lead's is told which flag differs, with both values.

#include "run_wide_args.hpp"

#include <gtest/gtest.h>

#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera::cli {
namespace {

OnlineOptions parsed(const std::vector<std::string>& argv) {
  const Arguments args(argv, {"refactor-growth", "local-threshold"}, {"no-local-rounds"});
  OnlineOptions o;
  parse_growth_and_local_rounds(args, o);
  return o;
}

std::string parse_error(const std::vector<std::string>& argv) {
  return test::input_error_of([&] { parsed(argv); });
}

TEST(RunWideArgs, AbsentFlagsLeaveTheOnlineDefaultsAndGivenOnesAreTaken) {
  const OnlineOptions defaults = parsed({});
  EXPECT_TRUE(defaults.solver.local_rounds.enabled);  // on in every online run
  EXPECT_EQ(defaults.solver.local_rounds.threshold, 1.0);
  EXPECT_EQ(defaults.refactor_growth, 0.0);
  const OnlineOptions given =
      parsed({"--refactor-growth", "0.1", "--local-threshold", "0.5", "--no-local-rounds"});
  EXPECT_FALSE(given.solver.local_rounds.enabled);
  EXPECT_EQ(given.solver.local_rounds.threshold, 0.5);
  EXPECT_EQ(given.refactor_growth, 0.1);
  EXPECT_NO_THROW(given.validate());
}

TEST(RunWideArgs, AnOutOfRangeGrowthOrThresholdIsNamed) {
  EXPECT_EQ(parse_error({"--refactor-growth", "-0.1"}),
            "option --refactor-growth: must be a finite number >= 0");
  EXPECT_NE(parse_error({"--refactor-growth", "inf"}).find("option --refactor-growth"),
            std::string::npos);
  for (const char* bad : {"0", "1.5", "-1"})
    EXPECT_EQ(parse_error({"--local-threshold", bad}),
              "option --local-threshold: must be in (0, 1]")
        << bad;
  EXPECT_NE(parse_error({"--local-threshold", "half"}).find("option --local-threshold: 'half'"),
            std::string::npos);
  EXPECT_EQ(parse_error({"--local-threshold", "1"}), "");  // the bound itself is in range
}

TEST(RunWideArgs, EqualOptionsAgreeAndTheFirstDifferenceIsNamedWithBothValues) {
  const RunWideOptions lead;
  EXPECT_EQ(run_wide_disagreement(lead, lead, 0), "");
  RunWideOptions off = lead;
  off.local_rounds = false;
  const std::string local = run_wide_disagreement(off, lead, 0);
  EXPECT_EQ(local.rfind("option --no-local-rounds: this agent's given differs from the lead's "
                        "(agent 0) absent; it decides which agents send their statuses",
                        0),
            0u)
      << local;
  RunWideOptions threshold = lead;
  threshold.local_threshold = 0.5;
  EXPECT_EQ(run_wide_disagreement(threshold, lead, 2)
                .rfind("option --local-threshold: this agent's 0.5 differs from the lead's "
                       "(agent 2) 1;",
                       0),
            0u);
  RunWideOptions growth = lead;
  growth.refactor_growth = 0.1;
  EXPECT_EQ(run_wide_disagreement(lead, growth, 1)
                .rfind("option --refactor-growth: this agent's 0 differs from the lead's "
                       "(agent 1) 0.1;",
                       0),
            0u);
  // The first flag that differs is named: --first-step-factors before the local rounds.
  RunWideOptions both = off;
  both.first_step_on_grown_factors = true;
  EXPECT_EQ(run_wide_disagreement(both, lead, 0).rfind("option --first-step-factors:", 0), 0u);
}

TEST(RunWideArgs, TheThresholdIsComparedOnlyWithLocalRoundsOn) {
  RunWideOptions mine, lead;
  mine.local_rounds = lead.local_rounds = false;
  mine.local_threshold = 0.25;
  EXPECT_EQ(run_wide_disagreement(mine, lead, 0), "");  // no local rounds: no threshold
  mine.local_rounds = lead.local_rounds = true;
  EXPECT_NE(run_wide_disagreement(mine, lead, 0), "");
}

}  // namespace
}  // namespace tessera::cli
