// The agents' distributed rounding (core/runtime/distributed_rounding.hpp) in process: one thread
// per agent over an in-memory channel, no DDS. Against core's round_solution (the direct
// translation solve) on iterates of the in-process distributed solver:
//  - from zero with only the residual stop it is the direct solve (positions to 1e-9);
//  - started from the iterate's translations with the cost stop (the defaults), the rounded
//    cost is within the documented bound of the direct solve's (cost_bound() * max(1, f(X))
//    above it, never below it by more than rounding error), in fewer CG iterations.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "rounding_threads.hpp"
#include "test_support.hpp"

namespace tessera::agent {
namespace {

// This file's grids (generator seed 3): grid_rounding_case (support/rounding_threads.hpp).
RoundingCase make_case(std::size_t poses, int agents, int max_rounds, bool partitioned = false) {
  return grid_rounding_case(poses, agents, max_rounds, partitioned, 3);
}

// Pose k's position in pose 0's frame: free of the rotation frame a rounding picks.
Eigen::VectorXd in_frame_of_pose_0(const std::vector<Pose>& p, std::size_t k) {
  return p[0].R.transpose() * (p[k].t - p[0].t);
}

double worst_position_gap(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  double worst = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    worst = std::max(worst, (in_frame_of_pose_0(a, k) - in_frame_of_pose_0(b, k)).norm());
  return worst;
}

TEST(DistributedRounding, FromZeroToTheResidualStopItIsTheDirectSolve) {
  const RoundingCase c = make_case(1000, 4, 20);
  for (bool coarse : {false, true}) {
    DistributedRoundingOptions exact;
    exact.interface_max_poses = 0;  // the CG
    exact.warm_start = false;
    exact.settle_tolerance = 0;
    exact.coarse_correction = coarse;
    const Rounded r = round_in_threads(c, exact);
    ASSERT_TRUE(r.errors.empty()) << r.errors.front();
    EXPECT_LT(worst_position_gap(r.poses, c.solved.poses), 1e-9) << "coarse " << coarse;
    EXPECT_NEAR(r.cost, c.solved.cost, 1e-12 * c.solved.cost) << "coarse " << coarse;
  }
}

// Block Jacobi alone moves a correction one block boundary per CG step, and the warm start
// after 5 rounds is off by smooth, block-sized shifts. The coarse level (one offset per block)
// removes those in each application: the same direct solve in far fewer all-agent steps at
// many compact blocks, and the default stop within its bound.
TEST(DistributedRounding, TheCoarseLevelReachesTheDirectSolveInFewerStepsAtManyBlocks) {
  const RoundingCase c = make_case(4000, 27, 5, true);
  std::uint32_t exact_steps[2] = {0, 0}, settled_steps[2] = {0, 0};
  for (bool coarse : {false, true}) {
    DistributedRoundingOptions exact;
    exact.interface_max_poses = 0;  // the CG
    exact.settle_tolerance = 0;
    exact.coarse_correction = coarse;
    const Rounded r = round_in_threads(c, exact);
    ASSERT_TRUE(r.errors.empty()) << r.errors.front();
    EXPECT_LT(worst_position_gap(r.poses, c.solved.poses), 1e-8) << "coarse " << coarse;
    DistributedRoundingOptions settled;
    settled.interface_max_poses = 0;
    settled.coarse_correction = coarse;
    const Rounded s = round_in_threads(c, settled);
    ASSERT_TRUE(s.errors.empty()) << s.errors.front();
    const double f_direct = evaluate_objective(c.graph, c.solved.poses);
    EXPECT_LE(s.cost - f_direct, settled.cost_bound() * std::max(1.0, c.solved.relaxation_cost))
        << "coarse " << coarse;
    EXPECT_GE(s.cost - f_direct, -1e-12 * f_direct) << "coarse " << coarse;
    exact_steps[coarse ? 1 : 0] = r.iterations;
    settled_steps[coarse ? 1 : 0] = s.iterations;
    std::printf("27 blocks, coarse %d: %u CG steps to 1e-12, %u to the default stop\n",
                coarse ? 1 : 0, r.iterations, s.iterations);
  }
  EXPECT_LT(exact_steps[1], exact_steps[0]);
  // At the default stop at least a quarter fewer (measured: 42 against 68).
  EXPECT_LT(4 * settled_steps[1], 3 * settled_steps[0])
      << settled_steps[1] << " with the coarse level, " << settled_steps[0] << " without";
}

TEST(DistributedRounding, WarmStartAndCostStopStayWithinTheBoundInFewerIterations) {
  for (int rounds : {20, 200}) {
    const RoundingCase c = make_case(1000, 4, rounds);
    DistributedRoundingOptions exact;
    exact.interface_max_poses = 0;  // the CG
    exact.warm_start = false;
    exact.settle_tolerance = 0;
    const Rounded cold = round_in_threads(c, exact);
    ASSERT_TRUE(cold.errors.empty()) << cold.errors.front();
    DistributedRoundingOptions defaults;  // the CG's
    defaults.interface_max_poses = 0;
    const Rounded warm = round_in_threads(c, defaults);
    ASSERT_TRUE(warm.errors.empty()) << warm.errors.front();
    // The direct solve's translations minimise the cost for the rounded rotations: the
    // inexact solve can only be above it, by at most the documented bound (cost_bound()).
    const double f_direct = evaluate_objective(c.graph, c.solved.poses);
    const double bound = defaults.cost_bound() * std::max(1.0, c.solved.relaxation_cost);
    EXPECT_LE(warm.cost - f_direct, bound) << "after " << rounds << " rounds";
    EXPECT_GE(warm.cost - f_direct, -1e-12 * f_direct) << "after " << rounds << " rounds";
    EXPECT_LE(evaluate_objective(c.graph, warm.poses) - f_direct, bound);
    // Starting from the iterate's translations and stopping when the cost is settled takes
    // fewer all-agent steps than the exact solve from zero.
    EXPECT_LT(warm.iterations, cold.iterations) << "after " << rounds << " rounds";
    std::printf(
        "after %d rounds: %u CG iterations from zero to 1e-12, %u warm to the cost "
        "bound; cost above the direct solve's %.3g (bound %.3g)\n",
        rounds, cold.iterations, warm.iterations, warm.cost - f_direct, bound);
  }
}

TEST(DistributedRounding, OptionsOutOfRangeNameTheField) {
  DistributedRoundingOptions o;
  o.settle_tolerance = -1;
  EXPECT_TRUE(test::validation_names(o, "settle_tolerance"));
  o = {};
  o.settle_window = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.interface_max_poses = 1000001;
  EXPECT_TRUE(test::validation_names(o, "interface_max_poses"));
  o = {};
  o.interface_one_factor_min_poses = 1000001;
  EXPECT_TRUE(test::validation_names(o, "interface_one_factor_min_poses"));
}

}  // namespace
}  // namespace tessera::agent
