// The coordinator's operator status lines (RunMonitor), without processes: what the line says
// about alive, lagging and lost agents, from round statuses and from progress digests.

#include "runtime/run_monitor.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>

#include "test_support.hpp"

namespace tessera::coordinator {
namespace {

using Clock = RunMonitor::Clock;
const Clock::time_point t0{};
Clock::time_point at(double s) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
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
    EXPECT_TRUE(test::validation_names(b.options, std::string("MonitorOptions.") + b.field))
        << b.field;
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

TEST(RunMonitor, FromDigestsNamesSilentAgentsAndTheAgentEveryLongWaiterWaitsFor) {
  std::ostringstream out;
  RunMonitor m(4, MonitorOptions{5.0, 2, 3.0}, out, t0);
  // Digests are samples: rounds far apart are no lag.
  m.on_digest(0, 100u, {}, 0.0, at(1));
  m.on_digest(1, 40u, {}, 0.0, at(1));
  m.on_digest(2, 70u, {2u}, 0.01, at(1));
  m.on_digest(3, 90u, {}, 0.0, at(1));
  EXPECT_EQ(m.line(at(1)), "status 1.0s: 4/4 agents alive; rounds 0:100 1:40 2:70 3:90");
  // Agent 3 hangs: its digests stop; the relay (0) waits for it alone, the others (no bundle
  // yet) for everyone but themselves.
  m.on_digest(0, 120u, {3u}, 3.5, at(4.5));
  m.on_digest(1, 119u, {0u, 2u, 3u}, 3.4, at(4.5));
  m.on_digest(2, 119u, {0u, 1u, 3u}, 3.4, at(4.5));
  EXPECT_EQ(m.line(at(4.5)),
            "status 4.5s: 4/4 agents alive; rounds 0:120 1:119 2:119 3:90; lagging: 3; agents "
            "0,1,2 wait for 3");
  m.tick(at(4.5));  // the lagging set changed: printed at once
  EXPECT_NE(out.str().find("lagging: 3"), std::string::npos) << out.str();
  // An agent done with the rounds (its final digest) sends no more: never lagging.
  RunMonitor done(2, MonitorOptions{5.0, 2, 3.0}, out, t0);
  done.on_digest(0, 9u, {}, 0.0, at(1), /*final=*/true);
  done.on_digest(1, 8u, {0u}, 4.0, at(5));
  EXPECT_EQ(done.line(at(5)), "status 5.0s: 2/2 agents alive; rounds 0:9 1:8");
  // A short wait names nobody.
  RunMonitor brief(2, MonitorOptions{5.0, 2, 3.0}, out, t0);
  brief.on_digest(0, 5u, {1u}, 0.2, at(1));
  brief.on_digest(1, 5u, {}, 0.0, at(1));
  EXPECT_EQ(brief.line(at(1)), "status 1.0s: 2/2 agents alive; rounds 0:5 1:5");
}

TEST(RunMonitor, NamesOnlyTheHungAgentNotTheOneBlockedOnItsMessages) {
  std::ostringstream out;
  RunMonitor m(3, MonitorOptions{5.0, 2, 3.0}, out, t0);
  m.on_digest(0, 10u, {}, 0.0, at(1));
  m.on_digest(2, 10u, {}, 0.0, at(1));
  m.on_digest(1, 10u, {}, 0.0, at(1.2));  // its last digest: it hangs
  // Agent 2 needs agent 1's poses before it can send its status: it waits in no step and
  // its digests go on. The relay (0) has sent its status and misses both others.
  m.on_digest(2, 10u, {}, 0.0, at(4.1));
  m.on_digest(0, 10u, {1u, 2u}, 3.05, at(4.1));
  // Agent 1 is not yet silent for lag_s, but it is the only quiet one of those waited for.
  EXPECT_EQ(m.line(at(4.1)),
            "status 4.1s: 3/3 agents alive; rounds 0:10 1:10 2:10; lagging: 1; agents 0 wait "
            "for 1");
  m.on_digest(2, 10u, {}, 0.0, at(4.5));
  m.on_digest(0, 10u, {1u, 2u}, 3.45, at(4.5));
  EXPECT_EQ(m.line(at(4.5)),
            "status 4.5s: 3/3 agents alive; rounds 0:10 1:10 2:10; lagging: 1; agents 0 wait "
            "for 1");
  // A slow agent whose digests go on (none quiet) is still named from the waits.
  RunMonitor slow(2, MonitorOptions{5.0, 2, 3.0}, out, t0);
  slow.on_digest(1, 5u, {}, 0.0, at(4.0));
  slow.on_digest(0, 5u, {1u}, 3.2, at(4.0));
  EXPECT_EQ(slow.line(at(4.0)),
            "status 4.0s: 2/2 agents alive; rounds 0:5 1:5; lagging: 1; agents 0 wait for 1");
}

}  // namespace
}  // namespace tessera::coordinator
