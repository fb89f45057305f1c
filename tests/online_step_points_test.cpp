// The estimates an online step passes through (step_points.hpp), from which a checkpoint's gap
// latency is taken: the step's data absorbed, each accepted Newton step, the step's end; their
// costs on the step's graph and how soon one is within a bound of that graph's optimum.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tessera/generate/generator.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/online/step_points.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

namespace tessera {
namespace {

// What a test sees of a step that kept its points.
struct KeptStep {
  OnlineUpdate update;
  PoseGraph graph;
  std::vector<StepPoint> points;
  Eigen::MatrixXd before;  // the iterate after the previous step that did work
  Eigen::MatrixXd after;   // the engine's iterate after this step
  std::vector<Pose> estimate;
};

struct Replay {
  GeneratorResult gen;
  std::vector<StreamBatch> batches;
};

Replay replay() {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kGrid3d;
  g.num_poses = 150;
  g.num_robots = 3;
  g.seed = 3;
  Replay r{generate_pose_graph(g), {}};
  ReplayOptions ro;
  ro.rate = 10;
  r.batches = plan_replay(r.gen.graph, r.gen.robot_of, ro).batches;
  return r;
}

OnlineOptions options(int threads) {
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-5;
  o.solver.max_rounds = 20000;
  o.solver.threads = threads;
  o.step_every_s = 0.5;
  o.certify_at_end = false;
  return o;
}

// Runs the replay keeping the points of the steps `keep` picks (by the count of steps begun,
// idle ones included); every step that did work is returned, with its points (empty when not
// kept).
std::vector<KeptStep> run_keeping(const Replay& r, const OnlineOptions& o,
                                  const std::function<bool(std::size_t)>& keep) {
  std::vector<KeptStep> steps;
  std::size_t begun = 0;
  Eigen::MatrixXd last;
  run_online(
      r.gen.graph.d, r.batches, o,
      [&](const OnlineEngine& engine, const OnlineUpdate& u) {
        steps.push_back({u, engine.stream().graph(), engine.step_points(), last, engine.iterate(),
                         engine.estimate()});
        last = engine.iterate();
      },
      [&](OnlineEngine& engine, std::size_t) { engine.keep_step_points(keep(begun++)); });
  return steps;
}

// The reference convention's f, summed here rather than by evaluate_objective.
double cost_by_hand(const PoseGraph& g, const std::vector<Pose>& p) {
  double f = 0.0;
  for (const Measurement& m : g.measurements) {
    const Pose& a = p[m.i];
    const Pose& b = p[m.j];
    f += m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
  }
  return f;
}

TEST(OnlineStepPoints,
     BeginAtTheAbsorbedEstimateEndAtTheStepsIterateAndReachTheBoundWithinTheStep) {
  const Replay r = replay();
  const std::vector<KeptStep> steps = run_keeping(r, options(1), [](std::size_t) { return true; });
  int checked = 0, newton_points = 0;
  for (const KeptStep& s : steps) {
    if (count_components(s.graph) != 1 || s.before.cols() == 0) continue;
    const OnlineUpdate& u = s.update;
    ASSERT_GE(s.points.size(), 2u);
    // First the absorbed estimate: the last step's iterate, the new poses appended to it.
    EXPECT_EQ(s.points.front().at, "absorbed");
    EXPECT_EQ(s.points.front().X.leftCols(s.before.cols()), s.before);
    EXPECT_EQ(s.points.front().X.cols(), s.after.cols());
    EXPECT_EQ(s.points.front().newton_steps, 0);
    EXPECT_EQ(s.points.front().cg_iterations, 0);
    // Last the step's own iterate, at the step's own times.
    EXPECT_EQ(s.points.back().at, "end");
    EXPECT_EQ(s.points.back().X, s.after);
    EXPECT_EQ(s.points.back().wall_s, u.ms / 1000.0);
    EXPECT_EQ(s.points.back().cpu_s, u.cpu_s);
    EXPECT_EQ(s.points.back().newton_steps, u.newton_steps);
    EXPECT_EQ(s.points.back().cg_iterations, u.newton_cg_iterations);
    for (std::size_t k = 1; k + 1 < s.points.size(); ++k) {
      EXPECT_EQ(s.points[k].at, "newton");
      EXPECT_LE(s.points[k - 1].wall_s, s.points[k].wall_s);
      EXPECT_LE(s.points[k - 1].cpu_s, s.points[k].cpu_s);
      // Counted up to the point, rejected Newton steps included.
      EXPECT_LT(s.points[k - 1].newton_steps, s.points[k].newton_steps);
      EXPECT_LE(s.points[k - 1].cg_iterations, s.points[k].cg_iterations);
      EXPECT_LE(s.points[k].newton_steps, u.newton_steps);
      EXPECT_LE(s.points[k].cg_iterations, u.newton_cg_iterations);
      ++newton_points;
    }
    EXPECT_LE(static_cast<int>(s.points.size()) - 2, u.newton_steps) << "accepted steps only";

    // The costs are the rounded estimates' on the step's graph; the gaps those against the
    // graph's optimum.
    const std::vector<StepPointCost> costs = cost_step_points(s.graph, s.points);
    ASSERT_EQ(costs.size(), s.points.size());
    EXPECT_EQ(costs.back().cost, evaluate_objective(s.graph, s.estimate));
    const double optimum = solve_centralized(s.graph).cost;
    const double wait_s = u.time_s - u.newest_publication_s;
    EXPECT_GE(wait_s, 0.0);
    const GapLatency gap = gap_latency(costs, optimum, 1e-3, wait_s);
    ASSERT_EQ(gap.rel_gaps.size(), costs.size());
    for (std::size_t k = 0; k < costs.size(); ++k) {
      const double by_hand = cost_by_hand(s.graph, round_solution(s.graph, s.points[k].X));
      EXPECT_NEAR(gap.rel_gaps[k], (by_hand - optimum) / optimum, 1e-12 * by_hand / optimum);
    }
    // Converged to 1e-5 at the end, so within the bound before the step is over.
    ASSERT_TRUE(gap.first.has_value());
    EXPECT_LE(gap.rel_gaps[*gap.first], 1e-3);
    EXPECT_LE(gap.wall_s, u.latency_s);
    EXPECT_LE(gap.cpu_s, u.latency_cpu_s);
    ++checked;
  }
  EXPECT_GE(checked, 3);
  EXPECT_GT(newton_points, 0);
}

TEST(OnlineStepPoints, OnlyTheStepsAskedForKeepPointsAndTheSolveIsTheSame) {
  const Replay r = replay();
  const std::vector<KeptStep> none = run_keeping(r, options(1), [](std::size_t) { return false; });
  const std::vector<KeptStep> odd =
      run_keeping(r, options(1), [](std::size_t k) { return k % 2 == 1; });
  ASSERT_EQ(none.size(), odd.size());
  int kept = 0;
  for (std::size_t k = 0; k < none.size(); ++k) {
    EXPECT_TRUE(none[k].points.empty());
    kept += odd[k].points.empty() ? 0 : 1;
    // Watching the trial points changes nothing in the iterates.
    EXPECT_EQ(none[k].after, odd[k].after);
    EXPECT_EQ(none[k].update.newton_cg_iterations, odd[k].update.newton_cg_iterations);
  }
  EXPECT_GT(kept, 0);
  EXPECT_LT(kept, static_cast<int>(none.size()));
}

TEST(OnlineStepPoints, TwoThreadsKeepTheSamePointsAsOne) {
  const Replay r = replay();
  const auto all = [](std::size_t) { return true; };
  const std::vector<KeptStep> one = run_keeping(r, options(1), all);
  const std::vector<KeptStep> two = run_keeping(r, options(2), all);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_EQ(one[k].points.size(), two[k].points.size());
    for (std::size_t p = 0; p < one[k].points.size(); ++p) {
      EXPECT_EQ(one[k].points[p].at, two[k].points[p].at);
      EXPECT_EQ(one[k].points[p].X, two[k].points[p].X);
    }
  }
}

// first_step_on_grown_factors: a step's first Newton step runs on the blocks' held factors
// with the new poses appended, so its point waits for fewer factorizations (none where every
// block's could be appended to); the blocks factor after it instead, no more often in the run,
// and the run ends where the default one does.
TEST(OnlineStepPoints, OnGrownFactorsTheFirstNewtonPointWaitsForNoFactorizationSameEnd) {
  const Replay r = replay();
  const auto all = [](std::size_t) { return true; };
  OnlineOptions o = options(1);
  const std::vector<KeptStep> fresh = run_keeping(r, o, all);
  o.first_step_on_grown_factors = true;
  const std::vector<KeptStep> grown = run_keeping(r, o, all);
  ASSERT_EQ(fresh.size(), grown.size());
  auto first_newton = [](const KeptStep& s) -> const StepPoint* {
    for (const StepPoint& p : s.points)
      if (p.at == "newton") return &p;
    return nullptr;
  };
  long long fresh_first = 0, grown_first = 0, fresh_all = 0, grown_all = 0;
  int compared = 0, without = 0;
  for (std::size_t k = 0; k < fresh.size(); ++k) {
    fresh_all += fresh[k].update.factorizations;
    grown_all += grown[k].update.factorizations;
    const StepPoint* f = first_newton(fresh[k]);
    const StepPoint* g = first_newton(grown[k]);
    if (!f || !g) continue;
    fresh_first += f->factorizations;
    grown_first += g->factorizations;
    // Counted up to the point: no more than the step did.
    EXPECT_LE(g->factorizations, grown[k].update.factorizations);
    EXPECT_EQ(grown[k].points.back().factorizations, grown[k].update.factorizations);
    // A block whose new poses could not be appended (TangentPreconditioner::grow) factors first.
    if (f->factorizations > 0 && g->factorizations == 0) ++without;
    ++compared;
  }
  EXPECT_GE(compared, 3);
  EXPECT_GT(without, 0);
  EXPECT_GT(fresh_first, 0);
  EXPECT_LT(grown_first, fresh_first);
  EXPECT_LE(grown_all, fresh_all);
  // The same optimum at the end (converged to 1e-5 both).
  const KeptStep& a = fresh.back();
  const KeptStep& b = grown.back();
  ASSERT_EQ(count_components(a.graph), 1u);
  const double optimum = solve_centralized(a.graph).cost;
  EXPECT_NEAR(evaluate_objective(a.graph, a.estimate), optimum, 1e-6 * optimum);
  EXPECT_NEAR(evaluate_objective(b.graph, b.estimate), optimum, 1e-6 * optimum);
}

StepPointCost point(double wall_s, double cost) {
  StepPointCost p;
  p.at = "newton";
  p.wall_s = wall_s;
  p.cpu_s = wall_s / 2;
  p.cost = cost;
  return p;
}

TEST(GapLatency, IsTheFirstPointWithinTheBoundPlusTheWaitAndInfiniteWithoutOne) {
  const std::vector<StepPointCost> points{point(0.1, 200.0), point(0.2, 100.05), point(0.3, 100.2),
                                          point(0.4, 100.01)};
  const GapLatency g = gap_latency(points, 100.0, 1e-3, 0.5);
  ASSERT_EQ(g.rel_gaps.size(), 4u);
  EXPECT_DOUBLE_EQ(g.rel_gaps[0], 1.0);
  EXPECT_EQ(g.first, 1u);  // within at the second point, above at the third, within again
  EXPECT_EQ(g.stays, 3u);
  EXPECT_DOUBLE_EQ(g.wall_s, 0.7);
  EXPECT_DOUBLE_EQ(g.cpu_s, 0.6);
  const GapLatency none = gap_latency({point(0.1, 200.0), point(0.2, 101.0)}, 100.0, 1e-3, 0.0);
  EXPECT_FALSE(none.first.has_value());
  EXPECT_FALSE(none.stays.has_value());
  EXPECT_EQ(none.wall_s, std::numeric_limits<double>::infinity());
  EXPECT_EQ(none.cpu_s, std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace tessera
