// The replay timeline and the in-process online engine: a replayed graph arrives whole, the
// online run ends at the batch optimum (also with a robot that starts late), and agents with
// nothing new idle.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <tessera/generate/generator.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>
#include <utility>

#include "test_support.hpp"

namespace tessera {
namespace {

GeneratorResult small_graph(TrajectoryKind kind, std::size_t n, std::size_t robots) {
  GeneratorOptions o;
  o.kind = kind;
  o.num_poses = n;
  o.num_robots = robots;
  o.seed = 3;
  return generate_pose_graph(o);
}

// A measurement by its original endpoints and values, for comparing graphs whose ids differ.
using EdgeKey = std::tuple<std::size_t, std::size_t, double, double, double>;

EdgeKey edge_key(const Measurement& m, std::size_t i, std::size_t j) {
  return {i, j, m.t(0), m.R(0, 0), m.kappa};
}

TEST(Replay, PublishesEveryMeasurementOnceBothPosesExistInTimeOrder) {
  const auto gen = small_graph(TrajectoryKind::kCity, 120, 3);
  ReplayOptions opt;
  opt.rate = 10;
  opt.speedup = 4;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, opt);
  EXPECT_EQ(plan.batches.size(), 120u);
  EXPECT_EQ(plan.measurements, gen.graph.measurements.size());
  EXPECT_DOUBLE_EQ(plan.duration_s, 39.0 / 10 / 4);
  EXPECT_TRUE(
      std::is_sorted(plan.batches.begin(), plan.batches.end(),
                     [](const StreamBatch& a, const StreamBatch& b) { return a.stamp < b.stamp; }));
  // Played in publication order, no measurement has to wait for a pose.
  GraphStream stream(gen.graph.d);
  for (const auto& b : plan.batches) {
    stream.absorb(b);
    EXPECT_EQ(stream.held_measurements(), 0u);
  }
  // Inter-robot closures are published by the robot that reached its pose last.
  for (const auto& b : plan.batches)
    for (const auto& m : b.measurements) {
      if (m.kind == MeasurementKind::kInterLoop) {
        EXPECT_TRUE(m.from.robot == b.robot || m.to.robot == b.robot);
      }
    }
}

TEST(Replay, OfAFileEqualsTheBatchGraphAtTheEnd) {
  const auto gen = small_graph(TrajectoryKind::kGrid3d, 150, 4);
  ReplayOptions opt;
  opt.start_s = {0.0, 3.0, 0.5, 7.0};  // late robots change the order, not the graph
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, opt);
  GraphStream stream(gen.graph.d);
  for (const auto& b : plan.batches) stream.absorb(b);
  const PoseGraph& got = stream.graph();
  ASSERT_EQ(got.num_poses, gen.graph.num_poses);
  ASSERT_EQ(got.measurements.size(), gen.graph.measurements.size());
  auto original = [&](std::size_t id) {
    const PoseKey k = stream.key_of_pose()[id];
    return plan.original_id[k.robot][k.index];
  };
  std::multiset<EdgeKey> want, have;
  for (const auto& m : gen.graph.measurements) want.insert(edge_key(m, m.i, m.j));
  for (const auto& m : got.measurements) have.insert(edge_key(m, original(m.i), original(m.j)));
  EXPECT_EQ(want, have);
  for (std::size_t id = 0; id < got.num_poses; ++id)
    EXPECT_EQ((got.initial[id].t - gen.graph.initial[original(id)].t).norm(), 0.0);
}

TEST(Replay, RejectsBadOptionsNamingTheField) {
  ReplayOptions o;
  o.rate = 0;
  EXPECT_TRUE(test::validation_names(o, "ReplayOptions.rate"));
  o = {};
  o.speedup = -1;
  EXPECT_TRUE(test::validation_names(o, "ReplayOptions.speedup"));
  o = {};
  o.start_s = {0.0, -2.0};
  EXPECT_TRUE(test::validation_names(o, "ReplayOptions.start_s[1]"));
}

OnlineOptions online_options() {
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-5;
  o.solver.max_rounds = 20000;
  return o;
}

double batch_optimum(const PoseGraph& g) {
  return solve_centralized(g).cost;
}

TEST(OnlineEngine, EndsAtTheBatchOptimumCertified) {
  const auto gen = small_graph(TrajectoryKind::kCity, 90, 3);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  const OnlineResult res = run_online(gen.graph.d, plan.batches, online_options());
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
  EXPECT_EQ(res.graph.measurements.size(), gen.graph.measurements.size());
  // One step per tick, and each ends with the gradient back under the tolerance (or stalled
  // a hair above it, where no update is accepted any more).
  EXPECT_EQ(res.updates.size(), 30u);
  for (const auto& u : res.updates) {
    EXPECT_TRUE(u.grad_norm <= 1e-5 || (u.stop_reason == "stalled" && u.grad_norm < 2e-5))
        << u.grad_norm << " " << u.stop_reason;
  }
}

TEST(OnlineEngine, ALateRobotJoinsAndTheFinalAnswerEqualsTheBatchOptimum) {
  const auto gen = small_graph(TrajectoryKind::kGrid3d, 96, 3);
  ReplayOptions ro;
  ro.rate = 10;
  ro.start_s = {0.0, 0.0, 4.0};  // robot 2 starts after robots 0 and 1 finished (3.1 s)
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  const OnlineResult res = run_online(gen.graph.d, plan.batches, online_options());
  // The run had two agents until robot 2's first pose, then three.
  EXPECT_EQ(res.updates.front().agents, 2);
  EXPECT_EQ(res.updates.back().agents, 3);
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
}

TEST(OnlineEngine, AgentsWithNoNewDataAndASmallGradientDoNothing) {
  const auto gen = small_graph(TrajectoryKind::kCity, 40, 2);
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ReplayOptions{});
  OnlineEngine engine(gen.graph.d, online_options());
  for (const auto& b : plan.batches) engine.receive(b);
  const OnlineUpdate first = engine.step(1.0);
  EXPECT_GT(first.rounds + first.newton_message_steps, 0);
  EXPECT_LE(first.grad_norm, 1e-5);
  const Eigen::MatrixXd before = engine.iterate();
  for (int k = 0; k < 3; ++k) {
    const OnlineUpdate idle = engine.step(2.0 + k);
    EXPECT_EQ(idle.rounds, 0);
    EXPECT_EQ(idle.newton_steps, 0);
    EXPECT_EQ(idle.bytes, 0u);
    EXPECT_EQ(idle.batches, 0u);
  }
  EXPECT_EQ((engine.iterate() - before).norm(), 0.0);
}

TEST(OnlineEngine, NewtonStepsEndEveryStepUnderTheToleranceWithoutARound) {
  const auto gen = small_graph(TrajectoryKind::kCity, 150, 3);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  OnlineOptions o = online_options();
  o.step_every_s = 0.5;
  o.certify_at_end = false;
  o.newton_steps = false;
  const OnlineResult rounds = run_online(gen.graph.d, plan.batches, o);
  o.newton_steps = true;
  const OnlineResult newton = run_online(gen.graph.d, plan.batches, o);
  int newton_messages = 0;
  for (const OnlineUpdate& u : newton.updates) {
    EXPECT_EQ(u.rounds, 0) << "Newton from the warm start, no round first";
    EXPECT_LE(u.grad_norm, 1e-5) << u.stop_reason;
    newton_messages += u.newton_message_steps;
  }
  EXPECT_EQ(newton.updates.size(), rounds.updates.size());
  EXPECT_GT(newton_messages, 0);
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(newton.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(rounds.cost, f_star, 1e-6 * f_star);
}

// The agents' messages handled on two threads (FIFO waves) give the same iterates, bit for
// bit, as one thread: with Newton steps and with rounds.
TEST(OnlineEngine, TwoThreadsGiveTheSameStepsAsOne) {
  const auto gen = small_graph(TrajectoryKind::kGrid3d, 120, 3);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  for (bool newton : {true, false}) {
    OnlineOptions o = online_options();
    o.step_every_s = 0.5;
    o.newton_steps = newton;
    const OnlineResult one = run_online(gen.graph.d, plan.batches, o);
    o.solver.threads = 2;
    const OnlineResult two = run_online(gen.graph.d, plan.batches, o);
    ASSERT_EQ(one.updates.size(), two.updates.size());
    for (std::size_t k = 0; k < one.updates.size(); ++k) {
      EXPECT_EQ(one.updates[k].rounds, two.updates[k].rounds);
      EXPECT_EQ(one.updates[k].newton_cg_iterations, two.updates[k].newton_cg_iterations);
      EXPECT_EQ(one.updates[k].grad_norm, two.updates[k].grad_norm);
      EXPECT_EQ(one.updates[k].bytes, two.updates[k].bytes);
    }
    EXPECT_EQ(one.cost, two.cost);
    ASSERT_TRUE(two.certified.has_value());
    EXPECT_TRUE(*two.certified);
  }
}

TEST(OnlineEngine, APoseThatOnlyExtendsOdometryNeedsNoRound) {
  // Composition puts the new pose where its odometry says: its measurement has no residual,
  // so the gradient does not move and the agents stay idle.
  const auto gen = small_graph(TrajectoryKind::kCity, 60, 1);
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ReplayOptions{});
  OnlineEngine engine(gen.graph.d, online_options());
  int rounds_on_odometry_only = 0, odometry_only_steps = 0;
  for (const auto& b : plan.batches) {
    engine.receive(b);
    const bool odometry_only =
        std::all_of(b.measurements.begin(), b.measurements.end(),
                    [](const auto& m) { return m.kind == MeasurementKind::kOdometry; });
    const OnlineUpdate u = engine.step(b.stamp);
    if (odometry_only && b.sequence > 0) {
      rounds_on_odometry_only += u.rounds + u.newton_steps;
      ++odometry_only_steps;
    }
  }
  EXPECT_GT(odometry_only_steps, 10);
  EXPECT_EQ(rounds_on_odometry_only, 0);
}

TEST(OnlineEngine, CertifiesWhileTheGraphGrowsWhenAsked) {
  const auto gen = small_graph(TrajectoryKind::kCity, 90, 3);
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ReplayOptions{});
  OnlineOptions o = online_options();
  o.certify_every_s = 1.0;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  // 3 s of stream: a certificate every second, robots that have not met yet included.
  ASSERT_FALSE(res.certificates.empty());
  double last = -1.0;
  for (const auto& c : res.certificates) {
    EXPECT_TRUE(c.certified) << "at " << c.time_s << " s, " << c.poses << " poses";
    // A certified iterate is kept as it is: no escape, the cost where the step left it.
    EXPECT_FALSE(c.escaped);
    EXPECT_NEAR(c.cost_after, c.cost_before, 1e-9 * c.cost_before);
    EXPECT_GE(c.time_s, last + 1.0);
    last = c.time_s;
  }
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
}

TEST(OnlineEngine, RobotsWhoseGuessesSitInUnrelatedFramesAreAlignedWhereTheyMeet) {
  auto gen = small_graph(TrajectoryKind::kGrid3d, 150, 3);
  // Each robot's front end guesses in a frame of its own (a long drift, or no common start):
  // a rotation of 2-3 rad and a shift per robot.
  ASSERT_TRUE(gen.graph.has_initial());
  for (std::size_t k = 0; k < gen.graph.num_poses; ++k) {
    const double r = static_cast<double>(gen.robot_of[k]);
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(2.0 + 0.4 * r, Eigen::Vector3d(1.0, r, 2.0 - r).normalized())
            .toRotationMatrix();
    Pose& p = gen.graph.initial[k];
    p.R = turn * p.R;
    p.t = turn * p.t + Eigen::Vector3d(40.0 * r, -25.0 * r, 10.0);
  }
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  OnlineOptions o = online_options();
  o.align_merged_pieces = true;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  std::size_t merges = 0, moved = 0;
  for (const auto& u : res.updates) {
    merges += u.merges;
    moved += u.merge_poses_moved;
  }
  // Three robots' pieces meet twice at least (robot pieces, and pieces a robot's own closures
  // join); the moved pieces are the smaller ones.
  EXPECT_GE(merges, 2u);
  EXPECT_GT(moved, 0u);
  EXPECT_LT(moved, merges * gen.graph.num_poses / 2);
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
}

// A ring of n poses (2D, noise-free: f* = 0) whose poses all arrive first, from guesses wound
// twice around it, and whose measurements all arrive a second later: the local search starts
// from a configuration that the rank-2 problem cannot unwind (every relative turn stays far from
// pi), so inside the iterate's 2-dimensional subspace it stops at a critical point far from
// the optimum; in the rank-5 problem that point is a saddle.
std::vector<StreamBatch> twice_wound_ring(std::size_t n) {
  const double pi = std::acos(-1.0), alpha = 2.0 * pi / static_cast<double>(n);
  auto rot = [](double a) {
    Eigen::Matrix2d R;
    R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    return R;
  };
  auto pose_at = [&](double angle, double radius) {
    Pose p;
    p.R = rot(angle + pi / 2);
    p.t = radius * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    return p;
  };
  StreamBatch poses, measurements;
  poses.stamp = 0.0;
  measurements.sequence = 1;
  measurements.stamp = 1.0;
  for (std::size_t k = 0; k < n; ++k) {
    StreamPose sp;
    sp.key = {0, k};
    sp.guess = pose_at(2.0 * alpha * static_cast<double>(k), 5.0);  // wound twice
    poses.poses.push_back(sp);
    const Pose a = pose_at(alpha * static_cast<double>(k), 10.0);  // the truth
    const Pose b = pose_at(alpha * static_cast<double>(k + 1), 10.0);
    StreamMeasurement m;
    m.from = {0, k};
    m.to = {0, (k + 1) % n};
    m.kind = k + 1 < n ? MeasurementKind::kOdometry : MeasurementKind::kIntraLoop;
    m.stamp = 1.0;
    m.relative.R = a.R.transpose() * b.R;
    m.relative.t = a.R.transpose() * (b.t - a.t);
    measurements.measurements.push_back(m);
  }
  return {poses, measurements};
}

TEST(OnlineEngine, AStreamThatStopsAtASaddleIsLeftByACertificateWhileStreaming) {
  const std::vector<StreamBatch> ring = twice_wound_ring(24);
  OnlineOptions o = online_options();
  o.certify_at_end = false;
  // Without a certificate the run ends where the local search stopped: gradient under the
  // tolerance, cost far above f* = 0.
  const OnlineResult stuck = run_online(2, ring, o);
  EXPECT_LE(stuck.grad_norm, 1e-5);
  EXPECT_GT(stuck.cost, 1.0);
  // A certificate after the step sees the saddle, the staircase leaves it, and the run goes on
  // from the climb's optimum brought back to rank 5: the batch optimum.
  o.certify_every_s = 0.5;
  const OnlineResult res = run_online(2, ring, o);
  ASSERT_EQ(res.certificates.size(), 1u);
  const OnlineCertificate& c = res.certificates.front();
  EXPECT_TRUE(c.escaped);
  EXPECT_GT(c.cost_before, 1.0);
  EXPECT_LT(c.cost_after, 1e-6);
  EXPECT_LT(res.cost, 1e-6);
  // The final certificate alone (the default) catches it too.
  OnlineOptions at_end = online_options();
  const OnlineResult end = run_online(2, ring, at_end);
  ASSERT_TRUE(end.certified.has_value());
  EXPECT_TRUE(*end.certified);
  EXPECT_LT(end.cost, 1e-6);
}

TEST(OnlineEngine, RejectsBadOptionsNamingTheField) {
  OnlineOptions o;
  o.solver.grad_norm_tol = -1;
  EXPECT_TRUE(test::validation_names(o, "OnlineOptions.solver: DistributedOptions.grad_norm_tol"));
  o = {};
  o.certify_every_s = -1;
  EXPECT_TRUE(test::validation_names(o, "OnlineOptions.certify_every_s"));
  o = {};
  o.rebalance.slack = -1;
  EXPECT_TRUE(test::validation_names(o, "RebalanceOptions.slack"));
  o = {};
  o.step_every_s = 0.5;
  o.real_time = true;
  EXPECT_TRUE(test::validation_names(o, "OnlineOptions.step_every_s"));
  o = {};
  o.newton_after_grad_tol = 0;
  EXPECT_TRUE(test::validation_names(o, "OnlineOptions.newton_after_grad_tol"));
  for (double bad : {0.0, 1.0, std::nan("")}) {
    o = {};
    o.newton_forcing = bad;
    EXPECT_TRUE(test::validation_names(o, "OnlineOptions.newton_forcing"));
  }
}

TEST(OnlineEngine, AFixedStepPeriodAbsorbsEachPeriodsBatchesAndEndsAtTheBatchOptimum) {
  const auto gen = small_graph(TrajectoryKind::kCity, 90, 3);
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ReplayOptions{});
  OnlineOptions o = online_options();
  o.step_every_s = 0.5;
  std::size_t batches = 0;
  double last = 0.0;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  for (const OnlineUpdate& u : res.updates) {
    // Steps at multiples of the period, each absorbing what was published since the last.
    EXPECT_NEAR(u.time_s / 0.5, std::round(u.time_s / 0.5), 1e-9) << u.time_s;
    EXPECT_GT(u.time_s, last);
    last = u.time_s;
    batches += u.batches;
  }
  EXPECT_EQ(batches, plan.batches.size());
  // 30 poses a robot at 10 per second: 3 s of stream, six periods (one step is the last).
  EXPECT_LE(res.updates.size(), 7u);
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
}

TEST(OnlineEngine, EachStepsCpuLatencyIsItsLatencyWithItsCpuTimeInPlaceOfItsWallTime) {
  const auto gen = small_graph(TrajectoryKind::kCity, 90, 3);
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ReplayOptions{});
  OnlineOptions o = online_options();
  o.step_every_s = 0.5;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  ASSERT_FALSE(res.updates.empty());
  for (const OnlineUpdate& u : res.updates) {
    EXPECT_GE(u.latency_cpu_s, 0.0);
    EXPECT_NEAR(u.latency_cpu_s, u.latency_s - u.ms / 1000.0 + u.cpu_s, 1e-9);
  }
  EXPECT_EQ(res.batch_latency_cpu_s.size(), res.batch_latency_s.size());
}

// Each step reports the tangent factorizations it did and their predicted flops; a block that
// keeps its factor while it grows (refactor_growth) does fewer of them and the run still ends at
// the batch optimum.
TEST(OnlineEngine, StepsCountTheirFactorizationsAndAKeptFactorStillReachesTheBatchOptimum) {
  const auto gen = small_graph(TrajectoryKind::kGrid3d, 300, 3);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  OnlineOptions o = online_options();
  o.step_every_s = 0.5;
  o.certify_at_end = false;
  auto totals = [](const OnlineResult& r) {
    long long factorizations = 0;
    double flops = 0.0;
    for (const OnlineUpdate& u : r.updates) {
      EXPECT_GE(u.factorizations, 0);
      EXPECT_EQ(u.factorizations > 0, u.factor_flops > 0.0);
      factorizations += u.factorizations;
      flops += u.factor_flops;
    }
    return std::make_pair(factorizations, flops);
  };
  const OnlineResult every = run_online(gen.graph.d, plan.batches, o);
  o.refactor_growth = 1.0;
  const OnlineResult kept = run_online(gen.graph.d, plan.batches, o);
  const auto [every_n, every_flops] = totals(every);
  const auto [kept_n, kept_flops] = totals(kept);
  // Without a kept factor every block that got new poses factors again at every step.
  EXPECT_GE(every_n, static_cast<long long>(every.updates.size()));
  EXPECT_LT(kept_n, every_n);
  EXPECT_LT(kept_flops, every_flops);
  const double f_star = batch_optimum(gen.graph);
  EXPECT_NEAR(every.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(kept.cost, f_star, 1e-6 * f_star);
}

}  // namespace
}  // namespace tessera
