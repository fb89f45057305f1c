// The agents' progress digests and what the coordinator makes of them (docs/dds-runtime.md,
// "Progress digests"), without processes: the digest an agent builds from the statuses it
// sends and receives (agent/progress_digest.hpp) and the rate-limited progress lines
// (runtime/progress_printer.hpp); the lag lines from digests: run_monitor_test.cpp; the round
// timing from agent 0's last digest: dds_round_reports_test.cpp.

#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "agent/progress_digest.hpp"
#include "coordinator/round_reports.hpp"
#include "runtime/progress_printer.hpp"
#include "runtime/stage_progress.hpp"

namespace {

using namespace tessera;
using Clock = std::chrono::steady_clock;

const Clock::time_point t0{};
Clock::time_point at(double s) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

RoundStatusMessage status(std::uint32_t round, std::uint32_t phase, std::uint32_t sender,
                          double cost, double grad_norm_sq) {
  RoundStatusMessage m;
  m.round = round;
  m.phase = phase;
  m.sender = sender;
  m.cost = cost;
  m.grad_norm_sq = grad_norm_sq;
  return m;
}

TEST(ProgressDigest, PeriodOutOfRangeIsAnErrorNamingTheField) {
  for (double bad : {0.0, -1.0, 61.0}) {
    try {
      agent::ProgressDigest d(0, 3, true, agent::ProgressDigestOptions{bad}, t0);
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("ProgressDigestOptions.period_s"), std::string::npos);
    }
  }
}

TEST(ProgressDigest, SumsCompletedStepsNamesMissingSendersAndTimesTheRounds) {
  agent::ProgressDigest d(1, 3, /*reporter=*/false, agent::ProgressDigestOptions{0.1}, t0);
  EXPECT_FALSE(d.due(at(0.05)));
  EXPECT_TRUE(d.due(at(0.1)));
  // Nothing completed yet: phase 0; waits in round 0 for agents 0 and 2 since it sent.
  d.on_status(status(0, 1, 1, 2.0, 0.25), true, at(0.1));
  d.on_status(status(0, 1, 0, 1.0, 0.5), false, at(0.12));
  d.on_status(status(0, 101, 2, 99.0, 99.0), false, at(0.12));  // a rounding status: ignored
  wire::AgentProgress p = d.take(at(0.3));
  EXPECT_EQ(p.sender(), 1u);
  EXPECT_EQ(p.phase(), 0u);
  EXPECT_EQ(p.waiting_for(), (std::vector<std::uint32_t>{2u}));
  EXPECT_EQ(p.waiting_round(), 0u);
  EXPECT_NEAR(p.waiting_s(), 0.2, 1e-9);
  EXPECT_EQ(p.completed_rounds(), 0u);
  EXPECT_FALSE(p.final());
  EXPECT_FALSE(d.due(at(0.35)));  // the period restarts with each digest
  // Agent 2's status completes round 0 (sums in agent-id order); a status of round 1 from a
  // faster agent may come before this agent sends its own.
  d.on_status(status(1, 1, 2, 0.5, 0.0), false, at(0.4));
  d.on_status(status(0, 1, 2, 4.0, 1.0), false, at(0.5));
  d.on_status(status(1, 1, 1, 0.25, 0.0), true, at(0.6));
  d.on_status(status(1, 1, 0, 0.125, 0.0), false, at(0.7));
  d.on_status(status(1, 5, 1, 0.0625, 0.0), true, at(0.8));  // a restart step
  d.on_status(status(1, 5, 0, 0.0625, 0.0), false, at(0.8));
  p = d.take(at(0.9), /*final=*/true);
  EXPECT_EQ(p.round(), 1u);
  EXPECT_EQ(p.phase(), 1u);
  EXPECT_EQ(p.cost(), 0.125 + 0.25 + 0.5);
  EXPECT_EQ(p.waiting_for(), (std::vector<std::uint32_t>{2u}));  // the restart step
  EXPECT_EQ(p.waiting_round(), 1u);
  EXPECT_EQ(p.completed_rounds(), 2u);
  EXPECT_NEAR(p.first_to_last_ms(), 200.0, 1e-6);  // round 0 at 0.5 s, round 1 at 0.7 s
  EXPECT_TRUE(p.final());
}

TEST(ProgressDigest, TheReporterSendsTheFirstStepAndRestartsAtOnce) {
  agent::ProgressDigest d(0, 2, /*reporter=*/true, agent::ProgressDigestOptions{10.0}, t0);
  d.on_status(status(0, 1, 0, 1.0, 0.0), true, at(0.01));
  EXPECT_FALSE(d.due(at(0.01)));
  d.on_status(status(0, 1, 1, 1.0, 0.0), false, at(0.02));
  EXPECT_TRUE(d.due(at(0.02)));  // the first completed step
  EXPECT_EQ(d.take(at(0.02)).phase(), 1u);
  d.on_status(status(1, 1, 0, 1.0, 0.0), true, at(0.03));
  d.on_status(status(1, 1, 1, 1.0, 0.0), false, at(0.03));
  EXPECT_FALSE(d.due(at(0.03)));  // an ordinary round waits for the period
  d.on_status(status(1, 5, 0, 1.0, 0.0), true, at(0.04));
  d.on_status(status(1, 5, 1, 1.0, 0.0), false, at(0.04));
  EXPECT_TRUE(d.due(at(0.04)));  // a restart
  const wire::AgentProgress p = d.take(at(0.04));
  EXPECT_EQ(p.round(), 1u);
  EXPECT_EQ(p.phase(), 5u);
  EXPECT_TRUE(p.waiting_for().empty());
}

TEST(ProgressPrinter, PrintsTheFirstRestartsAndTheLastAndAtMostOneLinePerInterval) {
  std::ostringstream out;
  coordinator::ProgressPrinter lines(true, out, 100.0);
  for (std::uint32_t k = 0; k < 50; ++k) lines.on_step({k, 1, 10.0 - k * 0.1, 4.0}, k * 5.0);
  lines.on_step({50, 5, 5.0, 4.0}, 250.0);  // a restart: printed whatever the interval
  lines.on_step({51, 1, 4.0, 1.0}, 255.0);
  lines.finish();
  const std::string s = out.str();
  EXPECT_EQ(s,
            "round 0: cost 10, grad norm 2.000e+00\n"
            "round 20: cost 8, grad norm 2.000e+00\n"
            "round 40: cost 6, grad norm 2.000e+00\n"
            "round 50 (restart): cost 5, grad norm 2.000e+00\n"
            "round 51: cost 4, grad norm 1.000e+00\n");
  std::ostringstream quiet;
  coordinator::ProgressPrinter off(false, quiet);
  off.on_step({0, 1, 1.0, 1.0}, 0.0);
  off.finish();
  EXPECT_TRUE(quiet.str().empty());
}

// The stages after the rounds: each stage progress report agent 0 sends
// (runtime/stage_progress.hpp) becomes one line, as the coordinator reads it.
TEST(ProgressPrinter, PrintsTheCertificateTheRefinementAndTheRoundingFromTheirReports) {
  std::ostringstream out;
  coordinator::RoundReports reports(true, out, 100.0);
  wire::AgentProgress round50;  // agent 0 saw round 50 complete
  round50.round(50);
  round50.phase(1);
  round50.cost(3.0);
  round50.grad_norm_sq(1e-4);
  reports.on_digest(round50, 0.0);
  reports.on_report(agent::StageProgressReport{agent::ProgressStage::kRefinement,
                                               agent::refinement_iteration(1, 0), 1.0e-2});
  reports.on_report(agent::StageProgressReport{agent::ProgressStage::kRefinement,
                                               agent::refinement_iteration(3, 412), 1.2e-3});
  reports.on_report(agent::StageProgressReport{agent::ProgressStage::kCertificate, 65, 0.8137});
  reports.on_report(agent::StageProgressReport{agent::ProgressStage::kRounding, 7, 2.5e-9});
  EXPECT_EQ(out.str(),
            "round 50: cost 3, grad norm 1.000e-02\n"
            "refinement: Newton step 1, CG iteration 0, gradient 1.000e-02\n"
            "refinement: Newton step 3, CG iteration 412, gradient 1.200e-03\n"
            "certificate: iteration 65, lambda_min estimate 8.137e-01\n"
            "rounding: translation CG iteration 7, cost moved by the last steps 2.500e-09\n");
}

}  // namespace
