// `tessera solve GRAPH --online --baseline`: the re-solving baseline of issue 24 counts one
// re-solve from scratch per publication that brought loop closures (or per closure, or per
// step), and a sample of them stands for all. A run says where it is on stderr while it goes.
// Its checkpoints say how soon the estimate came within a gap bound of their optimum.

#include <gtest/gtest.h>

#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/online/replay_schedule.hpp>

#include "runtime/replay_input.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// The number after `"key": ` in a flat JSON summary (the first occurrence).
double json_number(const std::string& json, const std::string& key) {
  const std::string tag = "\"" + key + "\": ";
  const std::size_t at = json.find(tag);
  if (at == std::string::npos) {
    ADD_FAILURE() << key << " missing in\n" << json;
    return -1.0;
  }
  return std::stod(json.substr(at + tag.size()));
}

struct Replay {
  std::string dir, graph;
  std::size_t closures = 0;      // loop closures of the replay (intra- and inter-robot)
  std::size_t publications = 0;  // batches with at least one
};

Replay generated() {
  Replay r;
  r.dir = test::temp_dir();
  r.graph = r.dir + "/g.g2o";
  std::string out;
  EXPECT_EQ(test::run_command(test::bin("tessera") +
                                  " generate --kind city --poses 120 --robots 2 --seed 1 --out " +
                                  r.graph,
                              &out),
            0)
      << out;
  const runtime::ReplayInput input = runtime::replay_input_from_file(r.graph, 2);
  const ReplayPlan plan = plan_replay(input.graph, input.robot_of_pose, ReplayOptions{});
  for (const StreamBatch& b : plan.batches) {
    std::size_t k = 0;
    for (const StreamMeasurement& m : b.measurements)
      k += m.kind != MeasurementKind::kOdometry ? 1 : 0;
    r.closures += k;
    r.publications += k > 0 ? 1 : 0;
  }
  return r;
}

std::string solve(const Replay& r, const std::string& extra) {
  const std::string json = r.dir + "/s.json";
  std::string out;
  const int rc = test::run_command(test::bin("tessera") + " solve " + r.graph +
                                       " --online --robots 2 --rate 10 --speedup 10 "
                                       "--step-every 0.1 --grad-tol 1e-2 --no-certify --baseline " +
                                       extra + " --json " + json,
                                   &out);
  EXPECT_EQ(rc, 0) << out;
  return test::read_text_file(json);
}

TEST(OnlineCli, TheBaselineReSolvesOncePerPublicationThatBroughtLoopClosures) {
  const Replay r = generated();
  ASSERT_GT(r.closures, 10u);
  ASSERT_LT(r.publications, r.closures);  // some batches hold several closures
  const std::string j = solve(r, "");
  EXPECT_EQ(json_number(j, "baseline_closures"), static_cast<double>(r.closures));
  EXPECT_EQ(json_number(j, "baseline_publications"), static_cast<double>(r.publications));
  // Every publication is counted once, except those whose graph still has a pose without a
  // measurement (none here: both robots' odometry starts before any closure), and every
  // counted one is re-solved.
  EXPECT_EQ(json_number(j, "baseline_skipped"), 0.0);
  EXPECT_EQ(json_number(j, "baseline_solves"), static_cast<double>(r.publications));
  EXPECT_EQ(json_number(j, "baseline_resolved"), static_cast<double>(r.publications));
  // A step of 0.1 s absorbs several of them: fewer closure steps than publications.
  EXPECT_LT(json_number(j, "baseline_closure_steps"), static_cast<double>(r.publications));
  EXPECT_GT(json_number(j, "baseline_cpu_s"), 0.0);
  EXPECT_NEAR(json_number(j, "baseline_cpu_s"), json_number(j, "baseline_measured_cpu_s"), 1e-9);
}

TEST(OnlineCli, PerClosureTheBaselineReSolvesOncePerClosureMeasurement) {
  const Replay r = generated();
  const std::string j = solve(r, "--baseline-per closure");
  EXPECT_EQ(json_number(j, "baseline_solves"), static_cast<double>(r.closures));
  EXPECT_EQ(json_number(j, "baseline_resolved"), static_cast<double>(r.closures));
}

TEST(OnlineCli, ASampleOfClosuresIsReSolvedAndScaledToAll) {
  const Replay r = generated();
  const std::string j = solve(r, "--baseline-samples 4");
  const double solves = json_number(j, "baseline_solves");
  const double resolved = json_number(j, "baseline_resolved");
  EXPECT_EQ(solves, static_cast<double>(r.publications));
  EXPECT_GE(resolved, 4.0);
  EXPECT_LE(resolved, 5.0);
  EXPECT_NEAR(json_number(j, "baseline_cpu_s"),
              json_number(j, "baseline_measured_cpu_s") * solves / resolved, 1e-6);
}

TEST(OnlineCli, PerStepTheBaselineReSolvesOncePerStepThatBroughtAClosure) {
  const Replay r = generated();
  const std::string j = solve(r, "--baseline-per step");
  EXPECT_EQ(json_number(j, "baseline_solves"), json_number(j, "baseline_closure_steps"));
  EXPECT_LT(json_number(j, "baseline_solves"), static_cast<double>(r.publications));
}

TEST(OnlineCli, TheBaselineReSolvesWithTheOnlineStepsNewtonStepsOrTheBatchRounds) {
  const Replay r = generated();
  const std::string rounds = solve(r, "--baseline-samples 4 --baseline-solver rounds");
  EXPECT_GT(json_number(rounds, "baseline_measured_rounds"), 0.0);
  EXPECT_EQ(json_number(rounds, "baseline_measured_cg_iterations"), 0.0);
  const std::string newton = solve(r, "--baseline-samples 4");  // the default
  EXPECT_GT(json_number(newton, "baseline_measured_cg_iterations"), 0.0);
  EXPECT_EQ(json_number(newton, "baseline_solves"), static_cast<double>(r.publications));
}

TEST(OnlineCli, TheStepsCoarseCorrectionReachesTheSameCertifiedOptimum) {
  const Replay r = generated();
  std::string out;
  auto run = [&](const std::string& extra) {
    const std::string json = r.dir + "/c.json";
    EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                    " --online --robots 2 --rate 10 --speedup 10 "
                                    "--step-every 0.1 --grad-tol 1e-4 " +
                                    extra + " --json " + json,
                                &out),
              0)
        << out;
    return test::read_text_file(json);
  };
  const std::string plain = run("");
  const std::string coarse = run("--step-coarse blocks");
  EXPECT_NEAR(json_number(coarse, "cost"), json_number(plain, "cost"),
              1e-8 * json_number(plain, "cost"));
  EXPECT_TRUE(test::contains(coarse, "\"certified\": true")) << coarse;
  const std::string smoothed = run("--step-coarse smoothed");
  EXPECT_NEAR(json_number(smoothed, "cost"), json_number(plain, "cost"),
              1e-8 * json_number(plain, "cost"));
  EXPECT_TRUE(test::contains(smoothed, "\"certified\": true")) << smoothed;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                  " --online --robots 2 --step-coarse pieces",
                              &out),
            2);
  EXPECT_TRUE(test::contains(out, "--step-coarse")) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                  " --online --robots 2 --step-coarse-min-blocks 1",
                              &out),
            2);
  EXPECT_TRUE(test::contains(out, "option --step-coarse-min-blocks")) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                  " --online --robots 2 --step-coarse-aggregates many",
                              &out),
            2);
  EXPECT_TRUE(test::contains(out, "option --step-coarse-aggregates")) << out;
}

TEST(OnlineCli, ARunSaysWhereItIsOnStderrUnlessToldNotTo) {
  const Replay r = generated();
  const std::string json = r.dir + "/p.json";
  const std::string cmd = test::bin("tessera") + " solve " + r.graph +
                          " --online --robots 2 --rate 10 --speedup 10 --step-every 0.1 "
                          "--grad-tol 1e-2 --no-certify --baseline --baseline-samples 2 "
                          "--checkpoints 2 --json " +
                          json;
  std::string out;
  ASSERT_EQ(test::run_command(cmd + " --progress-interval 0", &out), 0) << out;
  // A line after every step (interval 0), with the re-solves so far, then one per phase.
  EXPECT_TRUE(test::contains(out, "tessera solve --online: step 1, stream ")) << out;
  EXPECT_TRUE(test::contains(out, "re-solves")) << out;
  EXPECT_TRUE(test::contains(out, "batches absorbed in")) << out;
  EXPECT_TRUE(test::contains(out, "checkpoint 2 of 2")) << out;
  EXPECT_TRUE(test::contains(test::read_text_file(json), "\"complete\": true"));
  ASSERT_EQ(test::run_command(cmd + " --no-progress", &out), 0) << out;
  EXPECT_FALSE(test::contains(out, "tessera solve --online:")) << out;
  EXPECT_EQ(test::run_command(cmd + " --progress-interval -1", &out), 2);
  EXPECT_TRUE(test::contains(out, "--progress-interval")) << out;
}

TEST(OnlineCli, AnUnknownBaselineModeIsRefusedWithExitCode2) {
  const Replay r = generated();
  std::string out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                  " --online --robots 2 --baseline --baseline-per tick",
                              &out),
            2);
  EXPECT_TRUE(test::contains(out, "--baseline-per")) << out;
}

TEST(OnlineCli, UntilPlaysOnlyWhatWasPublishedByThenAndRefusesANegativeTime) {
  const Replay r = generated();
  // 60 poses a robot at 100 per second of stream: by 0.3 s each robot has published about 31.
  const std::string j = solve(r, "--until 0.3");
  EXPECT_GT(json_number(j, "poses"), 40.0);
  EXPECT_LT(json_number(j, "poses"), 80.0);
  // The load-free companion of the latency: the steps' CPU time in place of their wall time.
  EXPECT_GT(json_number(j, "latency_cpu_median_s"), 0.0);
  EXPECT_LE(json_number(j, "latency_cpu_median_s"), json_number(j, "latency_cpu_p95_s"));
  std::string out;
  EXPECT_EQ(
      test::run_command(
          test::bin("tessera") + " solve " + r.graph + " --online --robots 2 --until -1", &out),
      2);
  EXPECT_TRUE(test::contains(out, "--until")) << out;
}

TEST(OnlineCli, CheckpointsSayHowSoonTheEstimateCameWithinTheGapBound) {
  const Replay r = generated();
  const std::string j = solve(r, "--checkpoints 3 --gap-bound 1e-3");
  EXPECT_EQ(json_number(j, "gap_bound"), 1e-3);
  EXPECT_EQ(json_number(j, "gap_latency_missed"), 0.0);
  EXPECT_GE(json_number(j, "gap_latency_median_s"), 0.0);
  EXPECT_LE(json_number(j, "gap_latency_median_s"), json_number(j, "gap_latency_p95_s"));
  EXPECT_LE(json_number(j, "gap_latency_cpu_median_s"), json_number(j, "gap_latency_cpu_p95_s"));
  EXPECT_LE(json_number(j, "gap_cg_median"), json_number(j, "gap_cg_p95"));
  // The first checkpoint's: within the bound no later than its step's end.
  EXPECT_LE(json_number(j, "time_to_gap_s"), json_number(j, "step_latency_s"));
  EXPECT_TRUE(test::contains(j, "\"at\": \"absorbed\"")) << j;
  std::string out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + r.graph +
                                  " --online --robots 2 --checkpoints 2 --gap-bound 0",
                              &out),
            2);
  EXPECT_TRUE(test::contains(out, "--gap-bound")) << out;
}

TEST(OnlineCli, TheSummaryReportsTheSolverOptionsTheRunUsed) {
  const Replay r = generated();
  const std::string defaults = solve(r, "");
  for (const char* field :
       {"\"step_solver\": \"newton\"", "\"first_step_factors\": \"new\"",
        "\"tangent_dots\": \"split\"", "\"local_rounds\": true", "\"step_coarse\": "})
    EXPECT_TRUE(test::contains(defaults, field)) << field << " missing in\n" << defaults;
  EXPECT_EQ(json_number(defaults, "refactor_growth"), 0.0);
  EXPECT_EQ(json_number(defaults, "local_threshold"), 1.0);

  const std::string set = solve(r,
                                "--refactor-growth 0.25 --local-threshold 0.5 --first-step-factors "
                                "grown --tangent-dots sequential --step-coarse smoothed "
                                "--cut-fraction 0.05 --block-slack 0.3");
  for (const char* field : {"\"first_step_factors\": \"grown\"", "\"tangent_dots\": \"sequential\"",
                            "\"step_coarse\": \"smoothed\""})
    EXPECT_TRUE(test::contains(set, field)) << field << " missing in\n" << set;
  EXPECT_EQ(json_number(set, "refactor_growth"), 0.25);
  EXPECT_EQ(json_number(set, "local_threshold"), 0.5);
  EXPECT_EQ(json_number(set, "cut_fraction"), 0.05);
  EXPECT_EQ(json_number(set, "slack"), 0.3);
  EXPECT_TRUE(test::contains(solve(r, "--no-local-rounds"), "\"local_rounds\": false"));
}

}  // namespace
}  // namespace tessera
