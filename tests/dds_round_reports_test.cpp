// The coordinator's round reports (RoundReports), without processes: from round statuses (read
// while lost agents are arbitrated) a round completes when every active agent reported it, at
// the time its last status was read; from progress digests, the round timing and the last line
// come from agent 0's last digest (docs/dds-runtime.md, "Progress digests").

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

TEST(RoundReports, ARoundCompletesWithItsLastStatus) {
  std::ostringstream out;
  RoundReports r(true, out);
  r.on_round_status(status(0, 0), 5, 1.0);
  r.on_round_status(status(1, 0), 5, 1.0);
  // A fast agent is already in round 1.
  r.on_round_status(status(0, 1), 5, 2.0);
  r.on_round_status(status(2, 0), 5, 2.0);
  r.on_round_status(status(3, 0), 5, 2.0);
  EXPECT_EQ(r.results().completed_statuses, 0u);
  r.on_round_status(status(4, 0), 5, 3.0);
  EXPECT_EQ(r.results().completed_statuses, 1u);
  EXPECT_EQ(r.results().first_status_ms, 3.0);
  EXPECT_EQ(r.results().last_status_ms, 3.0) << "completed when its last status was read";
  EXPECT_NE(out.str().find("round 0: cost 5"), std::string::npos) << out.str();
}

TEST(RoundReports, RoundTimingAndTheLastLineComeFromAgentZerosFinalDigest) {
  std::ostringstream out;
  RoundReports reports(true, out);
  wire::AgentProgress d;
  d.sender(1);  // not the reporter: ignored
  d.round(3);
  d.phase(1);
  reports.on_digest(d, 10.0);
  EXPECT_TRUE(out.str().empty());
  d.sender(0);
  d.round(0);
  d.cost(9.0);
  reports.on_digest(d, 40.0);
  d.round(7);
  d.cost(4.0);
  reports.on_digest(d, 60.0);  // within 100 ms of the first line: held back
  d.round(9);
  d.cost(1.0);
  d.grad_norm_sq(0.01);
  d.completed_rounds(10);
  d.first_to_last_ms(90.0);
  d.final(true);
  reports.on_digest(d, 130.0);  // the last: always printed
  EXPECT_EQ(out.str(),
            "round 0: cost 9, grad norm 0.000e+00\nround 9: cost 1, grad norm 1.000e-01\n");
  const ReportedResults& r = reports.results();
  EXPECT_TRUE(r.have_final_digest);
  EXPECT_EQ(r.completed_statuses, 10u);
  EXPECT_EQ(r.first_status_ms, 40.0);
  EXPECT_EQ(r.last_status_ms, 130.0);
}

}  // namespace
}  // namespace tessera::coordinator

namespace tessera::coordinator {
namespace {

// Agent 0's own times (runtime/agent_report.hpp): solve and rounding seconds, and how the
// rounding solved its translations; none before the report came.
TEST(RoundReports, AgentZerosPhaseTimesAreKeptForTheSummary) {
  std::ostringstream out;
  RoundReports r(false, out);
  EXPECT_FALSE(r.results().phase_times.has_value());
  r.on_report(agent::PhaseTimesReport{0.25, 0.125, 12, 34, 5});
  ASSERT_TRUE(r.results().phase_times.has_value());
  EXPECT_EQ(r.results().phase_times->solve_s, 0.25);
  EXPECT_EQ(r.results().phase_times->rounding_s, 0.125);
  EXPECT_EQ(r.results().phase_times->rounding_cg_iterations, 12u);
  EXPECT_EQ(r.results().phase_times->rounding_interface_poses, 34u);
  EXPECT_EQ(r.results().phase_times->rounding_message_steps, 5u);
  EXPECT_FALSE(r.results().have_final_report);
}

// And its set-up (before the first round): initialisation and hand-off seconds, and whether
// the chordal start had been solved while the run started (runtime/early_chordal.hpp).
TEST(RoundReports, AgentZerosSetUpTimesAreKeptForTheSummary) {
  std::ostringstream out;
  RoundReports r(false, out);
  EXPECT_FALSE(r.results().setup.has_value());
  r.on_report(agent::SetupTimesReport{0.0625, 0.03125, true});
  ASSERT_TRUE(r.results().setup.has_value());
  EXPECT_EQ(r.results().setup->initialization_s, 0.0625);
  EXPECT_EQ(r.results().setup->handoff_s, 0.03125);
  EXPECT_TRUE(r.results().setup->initialization_early);
  r.on_report(agent::SetupTimesReport{0.0625, 0.03125, false});
  EXPECT_FALSE(r.results().setup->initialization_early);
}

// The final report ends the wait for reports; the certificate, its traffic and a robust run's
// decisions are kept as they came.
TEST(RoundReports, TheFinalReportAndTheCertificateAreKeptAsTheyCame) {
  std::ostringstream out;
  RoundReports r(false, out);
  agent::CertificateReport c;
  c.certified = true;
  c.min_eigenvalue = -1.5e-14;
  c.rounds = 1;
  c.final_rank = 5;
  c.bound.method = CertificateMethod::kExact;
  c.bound.lower_bound = 1025.25;
  r.on_report(c);
  r.on_report(agent::CertificateTrafficReport{142578, 0, 0});
  agent::RobustRunReport robust;
  robust.rejected = {3, 9};
  robust.outer_iterations = 29;
  r.on_report(robust);
  EXPECT_FALSE(r.results().have_final_report);
  r.on_report(agent::FinalReport{1025.5, 3e-9, 2});
  const ReportedResults& res = r.results();
  EXPECT_TRUE(res.have_final_report);
  EXPECT_EQ(res.final_report.cost, 1025.5);
  EXPECT_EQ(res.final_report.grad_norm, 3e-9);
  EXPECT_EQ(res.final_report.restarts, 2u);
  ASSERT_TRUE(res.certificate.has_value());
  EXPECT_TRUE(res.certificate->certified);
  EXPECT_EQ(res.certificate->bound.method, CertificateMethod::kExact);
  EXPECT_EQ(res.certificate->bound.lower_bound, 1025.25);
  EXPECT_EQ(res.certificate_bytes->certificate_bytes, 142578u);
  ASSERT_TRUE(res.robust.has_value());
  EXPECT_EQ(res.robust->rejected, (std::vector<std::size_t>{3, 9}));
  EXPECT_EQ(res.robust->outer_iterations, 29);
}

}  // namespace
}  // namespace tessera::coordinator
