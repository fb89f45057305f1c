// The coordinator's round reports (RoundReports), without processes: a round completes when
// every active agent reported it, and the wake-up threshold it gives the status inbox never
// asks for more statuses than can complete a round (the last round's completion used to wait
// for the final estimates, docs/dds-runtime.md, "Session 10 (stall10)").

#include <gtest/gtest.h>

#include <sstream>

#include "coordinator/round_reports.hpp"

namespace tessera::coordinator {
namespace {

wire::RoundStatus status(std::uint32_t sender, std::uint32_t round) {
  wire::RoundStatus m;
  m.sender(sender);
  m.round(round);
  m.phase(1);
  m.cost(1.0);
  return m;
}

TEST(RoundReports, WakeThresholdIsWhatTheRoundClosestToCompleteLacks) {
  std::ostringstream out;
  RoundReports r(true, out);
  EXPECT_EQ(r.statuses_to_complete(5), 5u) << "nothing partial: a whole round";
  // A wake-up took the first two statuses of round 0: three more complete it.
  r.on_round_status(status(0, 0), 5, 1.0);
  r.on_round_status(status(1, 0), 5, 1.0);
  EXPECT_EQ(r.statuses_to_complete(5), 3u);
  // A fast agent is already in round 1: round 0 still needs the fewest.
  r.on_round_status(status(0, 1), 5, 2.0);
  r.on_round_status(status(2, 0), 5, 2.0);
  r.on_round_status(status(3, 0), 5, 2.0);
  EXPECT_EQ(r.statuses_to_complete(5), 1u);
  EXPECT_EQ(r.results().completed_statuses, 0u);
  r.on_round_status(status(4, 0), 5, 3.0);
  EXPECT_EQ(r.results().completed_statuses, 1u);
  EXPECT_EQ(r.results().last_status_ms, 3.0) << "completed when its last status was read";
  EXPECT_EQ(r.statuses_to_complete(5), 4u) << "round 1 has one of five";
  EXPECT_NE(out.str().find("round 0: cost 5"), std::string::npos) << out.str();
  r.drop_partial_rounds();
  EXPECT_EQ(r.statuses_to_complete(5), 5u);
  EXPECT_EQ(r.statuses_to_complete(0), 1u) << "never 0 (a threshold of 0 would never wake)";
}

}  // namespace
}  // namespace tessera::coordinator
