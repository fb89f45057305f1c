// The coordinator's decisions on lost agents (RejoinArbiter) and its operator status lines
// (RunMonitor), without processes: which rollback round is chosen, when it gives up, and what
// the status line says about alive, lagging and lost agents.

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>

#include "runtime/rejoin_arbiter.hpp"
#include "runtime/run_monitor.hpp"

namespace tessera::coordinator {
namespace {

using Kind = LossDecision::Kind;
const Clock::time_point t0 = Clock::now();
Clock::time_point at(double s) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

TEST(RejoinArbiter, WaitsThenRollsBackToTheNewestCheckpointRoundEveryoneReached) {
  RejoinArbiter a(3, 10.0);
  for (std::uint32_t k = 0; k < 3; ++k) a.on_status(k, 7);
  a.on_status(0, 8);
  EXPECT_EQ(a.decide(at(0)).kind, Kind::kWait);
  a.on_lost(1, at(1));
  EXPECT_EQ(a.decide(at(5)).kind, Kind::kWait) << "inside the rejoin window";
  // Checkpoints at 6 and 8: agent 2 only reached 7, so 8 is not common; 6 is.
  a.on_rejoin({1, 8, 6, 42}, at(6));
  LossDecision d = a.decide(at(6));
  ASSERT_EQ(d.kind, Kind::kRollback);
  EXPECT_EQ(d.round, 6u);
  EXPECT_EQ(d.epoch, 1u);
  ASSERT_EQ(d.rejoined.size(), 1u);
  EXPECT_EQ(d.rejoined[0].nonce, 42u);
  EXPECT_FALSE(a.anyone_lost());
  EXPECT_EQ(a.decide(at(7)).kind, Kind::kWait);
  // A second loss: everyone reached 9 by now, the newest checkpoint wins; the epoch grows.
  for (std::uint32_t k = 0; k < 3; ++k) a.on_status(k, 9);
  a.on_rejoin({2, 9, 8, 7}, at(8));  // a rejoin before the loss was noticed counts as one
  d = a.decide(at(8));
  ASSERT_EQ(d.kind, Kind::kRollback);
  EXPECT_EQ(d.round, 9u);
  EXPECT_EQ(d.epoch, 2u);
}

TEST(RejoinArbiter, GivesUpWhenNobodyComesBackOrNoRoundIsCommon) {
  RejoinArbiter a(2, 3.0);
  a.on_status(0, 4);
  a.on_status(1, 4);
  a.on_lost(0, at(0));
  EXPECT_EQ(a.decide(at(2.9)).kind, Kind::kWait);
  const LossDecision d = a.decide(at(3.0));
  ASSERT_EQ(d.kind, Kind::kGiveUp);
  EXPECT_EQ(d.agent, 0u);
  EXPECT_NE(d.reason.find("did not rejoin within 3 s"), std::string::npos) << d.reason;

  RejoinArbiter b(2, 3.0);
  b.on_status(0, 2);
  b.on_status(1, 2);
  b.on_rejoin({1, 6, 5, 1}, at(0));  // agent 0 never reached 5
  const LossDecision e = b.decide(at(0));
  ASSERT_EQ(e.kind, Kind::kGiveUp);
  EXPECT_NE(e.reason.find("rounds reached: 0:2"), std::string::npos) << e.reason;

  RejoinArbiter off(2, 0.0);
  off.on_lost(1, at(0));
  EXPECT_EQ(off.decide(at(0)).kind, Kind::kGiveUp);
}

TEST(RunMonitor, OptionsOutOfRangeAreErrorsNamingTheField) {
  EXPECT_NO_THROW(MonitorOptions{}.validate());
  EXPECT_NO_THROW((MonitorOptions{0.0, 1, 0.5}.validate()));  // 0 = only on changes
  const struct {
    MonitorOptions options;
    const char* field;
  } bad[] = {{{-1.0, 2, 3.0}, "interval_s"},
             {{1e9, 2, 3.0}, "interval_s"},
             {{std::nan(""), 2, 3.0}, "interval_s"},
             {{5.0, 0, 3.0}, "lag_rounds"},
             {{5.0, 2, 0.0}, "lag_s"},
             {{5.0, 2, std::nan("")}, "lag_s"}};
  for (const auto& b : bad) {
    try {
      b.options.validate();
      ADD_FAILURE() << "accepted a bad " << b.field;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("MonitorOptions.") + b.field),
                std::string::npos)
          << e.what();
    }
    std::ostringstream out;
    EXPECT_THROW(RunMonitor(3, b.options, out, t0), InputError) << b.field;
  }
}

TEST(RunMonitor, ReportsAliveRoundsLaggingAndLostAgents) {
  std::ostringstream out;
  RunMonitor m(3, MonitorOptions{5.0, 2, 3.0}, out, t0);
  m.on_status(0, 10, at(1));
  m.on_status(1, 10, at(1));
  m.on_status(2, 7, at(1));
  EXPECT_EQ(m.line(at(1)), "status 1.0s: 3/3 agents alive; rounds 0:10 1:10 2:7; lagging: 2");
  m.tick(at(1));  // lagging set changed: printed at once
  EXPECT_NE(out.str().find("lagging: 2"), std::string::npos) << out.str();
  m.on_status(2, 10, at(2));
  m.set_lost({1}, at(2.5));
  EXPECT_NE(out.str().find("status 2.5s: agent 1 lost"), std::string::npos) << out.str();
  EXPECT_EQ(m.line(at(2.5)), "status 2.5s: 2/3 agents alive; rounds 0:10 1:10 2:10; lost: 1");
  // Silent while another agent reports: lagging after lag_s.
  m.on_status(0, 11, at(6));
  EXPECT_NE(m.line(at(6)).find("lagging: 2"), std::string::npos) << m.line(at(6));
  m.set_lost({}, at(7));
  EXPECT_NE(out.str().find("agent 1 is back"), std::string::npos) << out.str();
  const std::size_t before = out.str().size();
  m.tick(at(7.5));
  m.tick(at(13));
  EXPECT_GT(out.str().size(), before) << "a periodic line after the interval";
}

}  // namespace
}  // namespace tessera::coordinator
