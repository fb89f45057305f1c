// The online Newton steps' coarse correction (OnlineOptions::newton_coarse = kBlocks: one rigid
// motion per block in the CG's preconditioner) on robots that have not met: each robot's block
// is a piece of the map of its own, whose rigid motions leave f unchanged, so the correction is
// empty there and the steps are block Jacobi's; once the robots meet it cuts CG iterations and
// the run still ends at the batch optimum.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <tessera/generate/generator.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/online/stream_batch.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

namespace tessera {
namespace {

GeneratorResult grid(std::size_t n, std::size_t robots) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = n;
  o.num_robots = robots;
  o.seed = 3;
  return generate_pose_graph(o);
}

OnlineOptions options(NewtonRefineOptions::Coarse coarse) {
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-5;
  o.step_every_s = 0.5;
  o.certify_at_end = false;
  o.newton_coarse = coarse;
  return o;
}

int cg_iterations(const OnlineResult& r) {
  int cg = 0;
  for (const OnlineUpdate& u : r.updates) cg += u.newton_cg_iterations;
  return cg;
}

TEST(OnlineCoarse, RobotsThatHaveNotMetTakeTheSameNewtonStepsAsWithoutTheCorrection) {
  // The replay without its inter-robot measurements: three pieces that never meet. Before the
  // correction projected out each piece's own rigid motions, it inverted A's round-off there
  // (821 Newton steps against 310 on the first 5,010 poses of a 10,000-pose grid).
  const auto gen = grid(240, 3);
  ReplayOptions ro;
  ro.rate = 10;
  ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  for (StreamBatch& b : plan.batches)
    b.measurements.erase(
        std::remove_if(b.measurements.begin(), b.measurements.end(),
                       [](const StreamMeasurement& m) { return m.from.robot != m.to.robot; }),
        b.measurements.end());
  const OnlineResult none =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kNone));
  const OnlineResult blocks =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kBlocks));
  ASSERT_EQ(blocks.updates.size(), none.updates.size());
  int steps = 0;
  for (std::size_t k = 0; k < none.updates.size(); ++k) {
    EXPECT_EQ(blocks.updates[k].newton_steps, none.updates[k].newton_steps) << "step " << k;
    EXPECT_EQ(blocks.updates[k].newton_cg_iterations, none.updates[k].newton_cg_iterations)
        << "step " << k;
    EXPECT_EQ(blocks.updates[k].rounds, 0) << "step " << k;
    steps += none.updates[k].newton_steps;
  }
  EXPECT_GT(steps, 0);
  EXPECT_NEAR(blocks.grad_norm, none.grad_norm, 1e-9);
}

TEST(OnlineCoarse, OnceTheRobotsMeetItTakesFewerCgIterationsToTheBatchOptimum) {
  const auto gen = grid(600, 4);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  const OnlineResult none =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kNone));
  const OnlineResult blocks =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kBlocks));
  EXPECT_LT(cg_iterations(blocks), cg_iterations(none));
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(none.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(blocks.cost, f_star, 1e-6 * f_star);
  std::printf("CG iterations: block Jacobi %d, with the blocks' rigid motions %d\n",
              cg_iterations(none), cg_iterations(blocks));
}

}  // namespace
}  // namespace tessera
