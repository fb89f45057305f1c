// The block update's number of trust-region steps: the adaptive stop on the block gradient
// (BlockUpdateOptions::grad_reduction) and IRBCD's own setting of it (DistributedOptions::
// irbcd_trust_region_steps / irbcd_grad_reduction), which RBCD and RBCD++ must not see.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/block_preconditioner.hpp>

#include "lifted_blocks.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// A block away from its minimiser (neighbours fixed), so that several steps keep moving it.
struct PerturbedBlock {
  BlockProblem problem;
  Eigen::MatrixXd start;
  double start_grad_norm = 0.0;
};

PerturbedBlock perturbed_block(int d, std::uint64_t seed) {
  const test::HalfBlock hb = test::half_block(d, seed);
  BlockProblem problem(d, hb.owned, hb.graph.measurements);
  const int r = 5;
  const Eigen::MatrixXd X = lift_poses(hb.graph.initial, r);
  problem.set_neighbor_poses(gather_pose_columns(X, problem.neighbors(), d));
  const LiftedManifold M = problem.manifold(r);
  const Eigen::MatrixXd Y0 = gather_pose_columns(X, hb.owned, d);
  std::srand(static_cast<unsigned>(seed));
  const Eigen::MatrixXd v = M.tangent_project(Y0, Eigen::MatrixXd::Random(r, Y0.cols()));
  Eigen::MatrixXd start = M.retract(Y0, 0.5 * v);
  const double g0 = problem.riemannian_gradient(start, problem.euclidean_gradient(start)).norm();
  return {std::move(problem), std::move(start), g0};
}

struct Update {
  Eigen::MatrixXd X;
  double grad_norm = 0.0;
  BlockUpdateStats stats;
};

Update run(const PerturbedBlock& b, int steps, double grad_reduction) {
  BlockUpdateOptions o;
  o.tangent_preconditioner = false;
  o.trust_region_steps = steps;
  o.grad_reduction = grad_reduction;
  BlockPreconditioner precon(b.problem);
  Update u;
  double gsq = 0.0;
  u.X = block_update(b.problem, b.start, o, &precon, &gsq, nullptr, &u.stats);
  u.grad_norm = std::sqrt(gsq);
  return u;
}

// With K steps allowed, the update stops after the first step exactly when that step brought
// the block gradient to grad_reduction of its start value or below; otherwise it goes on, and
// then it is the plain K-step update, bit for bit.
TEST(BlockUpdate, GradReductionEndsAMultiStepUpdateOnceTheBlockGradientFell) {
  for (int d : {2, 3}) {
    const PerturbedBlock b = perturbed_block(d, 5 + d);
    const Update one = run(b, 1, 0.0);
    const Update two = run(b, 2, 0.0);
    const double reduction = one.grad_norm / b.start_grad_norm;
    ASSERT_LT(reduction, 0.99) << "d = " << d;  // the first step moved towards the minimiser
    ASSERT_GT(reduction, 1e-6) << "d = " << d;  // and did not reach it: a second step matters
    EXPECT_GT((two.X - one.X).norm(), 0.0);
    EXPECT_LT(two.grad_norm, one.grad_norm);
    EXPECT_GT(two.stats.trust_region_iterations, one.stats.trust_region_iterations);

    const Update stopped = run(b, 2, std::min(0.999, reduction * 1.01));
    EXPECT_EQ(stopped.X, one.X) << "d = " << d;
    EXPECT_EQ(stopped.stats.trust_region_iterations, one.stats.trust_region_iterations);
    EXPECT_EQ(stopped.stats.tcg_iterations, one.stats.tcg_iterations);

    const Update continued = run(b, 2, reduction * 0.99);
    EXPECT_EQ(continued.X, two.X) << "d = " << d;
    EXPECT_EQ(continued.grad_norm, two.grad_norm);
  }
}

TEST(BlockUpdate, IrbcdSettingsApplyToIrbcdOnly) {
  DistributedOptions o;
  // Defaults: IRBCD may take a second step (docs/irbcd.md section 5), RBCD++ takes one.
  o.algorithm = DistributedAlgorithm::kIrbcd;
  EXPECT_EQ(o.algorithm_block_update().trust_region_steps, 2);
  EXPECT_EQ(o.algorithm_block_update().grad_reduction, 0.2);
  o.algorithm = DistributedAlgorithm::kRbcdPlusPlus;
  EXPECT_EQ(o.algorithm_block_update().trust_region_steps, 1);
  EXPECT_EQ(o.algorithm_block_update().grad_reduction, 0.0);
  o.block_update.trust_region_steps = 1;
  o.block_update.grad_reduction = 0.0;
  o.irbcd_trust_region_steps = 12;  // above block_update.max_attempts (10): raised with it
  o.irbcd_grad_reduction = 0.3;
  for (DistributedAlgorithm a :
       {DistributedAlgorithm::kRbcd, DistributedAlgorithm::kRbcdPlusPlus}) {
    o.algorithm = a;
    EXPECT_EQ(o.algorithm_block_update().trust_region_steps, 1) << algorithm_name(a);
    EXPECT_EQ(o.algorithm_block_update().grad_reduction, 0.0) << algorithm_name(a);
  }
  o.algorithm = DistributedAlgorithm::kIrbcd;
  EXPECT_EQ(o.algorithm_block_update().trust_region_steps, 12);
  EXPECT_EQ(o.algorithm_block_update().max_attempts, 12);
  EXPECT_EQ(o.algorithm_block_update().grad_reduction, 0.3);
  EXPECT_NO_THROW(o.validate());
  // Unset (0 steps, negative reduction): IRBCD takes block_update's values too.
  o.irbcd_trust_region_steps = 0;
  o.irbcd_grad_reduction = -1.0;
  o.block_update.trust_region_steps = 3;
  o.block_update.grad_reduction = 0.1;
  EXPECT_EQ(o.algorithm_block_update().trust_region_steps, 3);
  EXPECT_EQ(o.algorithm_block_update().grad_reduction, 0.1);
}

TEST(BlockUpdate, OptionsAreValidated) {
  using test::validation_names;
  DistributedOptions o;
  o.block_update.grad_reduction = 1.0;
  EXPECT_TRUE(validation_names(o, "grad_reduction"));
  o = {};
  o.block_update.grad_reduction = -0.5;
  EXPECT_TRUE(validation_names(o, "grad_reduction"));
  o = {};
  o.irbcd_trust_region_steps = -1;
  EXPECT_TRUE(validation_names(o, "irbcd_trust_region_steps"));
  o = {};
  o.irbcd_grad_reduction = 1.0;
  EXPECT_TRUE(validation_names(o, "irbcd_grad_reduction"));
}

}  // namespace
}  // namespace tessera
