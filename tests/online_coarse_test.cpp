// The online Newton steps' coarse corrections (OnlineOptions::newton_coarse): kBlocks, one rigid
// motion per block in the CG's preconditioner, and kSmoothed, rigid motions of smoothed pieces
// inside the blocks built from the linked graph at every solve. On robots that have not met,
// each robot's block is a piece of the map of its own whose rigid motions leave f unchanged, so
// the correction is empty there and the steps are block Jacobi's; once the robots meet both cut
// CG iterations (the smoothed pieces more than the blocks' rigid motions) and the run still ends
// at the batch optimum. The smoothed correction's coarse inverse, from a Cholesky factor, is the
// pseudo-inverse of its Galerkin matrix, so the preconditioner is the same symmetric positive
// definite one.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/online/stream_batch.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <utility>
#include <vector>

#include "distributed/tangent_coarse_space.hpp"
#include "generate/robot_ranges.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// Blocks 0 and 1 hold one chain, block 2 a chain of its own (a robot that has met no other).
BlockLayout two_groups() {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t i = 0; i + 1 < 30; ++i) edges.emplace_back(i, i + 1);
  for (std::uint32_t i = 30; i + 1 < 45; ++i) edges.emplace_back(i, i + 1);
  std::vector<int> parts(45, 0);
  for (std::size_t i = 15; i < 45; ++i) parts[i] = i < 30 ? 1 : 2;
  return make_block_layout(45, edges, parts);
}

// set_matrix's A x and A^+ x against A and pseudo_inverse(A) for a symmetric A.
void expect_kept_matrix_is_the_pseudo_inverse(const Eigen::MatrixXd& A) {
  const BlockLayout layout = two_groups();
  TangentCoarseSpace c(nullptr, layout, layout.poses[0], {15}, 3, 3);
  std::vector<double> packed;
  c.pack(A, packed);
  ASSERT_EQ(packed.size(), c.packed_size());
  // Only blocks 0 and 1 (one group, 2 x 6 unknowns) are carried.
  EXPECT_EQ(c.packed_size(), 12u * 13u / 2u);
  c.set_matrix(packed.data());
  const Eigen::MatrixXd inv = c.pseudo_inverse(A);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const int g = c.generators();
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x(c.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = normal(rng);
    const Eigen::VectorXd y = c.times_inverse(x);
    EXPECT_LT((y - inv * x).norm(), 1e-10 * (inv * x).norm()) << "trial " << trial;
    // Block 2's unknowns: nothing (all gauge).
    EXPECT_EQ(y.segment(2 * g, g).norm(), 0.0);
    // A x over the group only (A is zero between groups and on a lone piece).
    Eigen::VectorXd ax = Eigen::VectorXd::Zero(c.size());
    ax.head(2 * g) = A.topLeftCorner(2 * g, 2 * g) * x.head(2 * g);
    EXPECT_LT((c.times_matrix(x) - ax).norm(), 1e-12 * ax.norm());
  }
}

TEST(OnlineSmoothedCoarse, TheCholeskyInverseIsThePseudoInverseOfTheGalerkinMatrix) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd M(18, 18);
  for (Eigen::Index i = 0; i < M.size(); ++i) M.data()[i] = normal(rng);
  // Positive definite: the Cholesky path.
  expect_kept_matrix_is_the_pseudo_inverse(M * M.transpose() + Eigen::MatrixXd::Identity(18, 18));
  // Indefinite (negative curvature along some combination): the eigendecomposition's fallback,
  // which drops the negative eigenvalues as pseudo_inverse does.
  expect_kept_matrix_is_the_pseudo_inverse(M + M.transpose());
}

TEST(OnlineSmoothedCoarse, KeptApartTheInvertedMatrixAndTheGalerkinMatrixEachDoTheirPart) {
  // set_matrices: A^+ x from the inverted (data part) matrix, A x from the Galerkin one, which
  // balancing needs for the Hessian's own products.
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd M(18, 18);
  for (Eigen::Index i = 0; i < M.size(); ++i) M.data()[i] = normal(rng);
  const Eigen::MatrixXd D = M * M.transpose() + Eigen::MatrixXd::Identity(18, 18);
  const Eigen::MatrixXd H = M + M.transpose();  // indefinite
  const BlockLayout layout = two_groups();
  TangentCoarseSpace c(nullptr, layout, layout.poses[0], {15}, 3, 3);
  std::vector<double> d, h;
  c.pack(D, d);
  c.pack(H, h);
  c.set_matrices(d.data(), h.data());
  const Eigen::MatrixXd inv = c.pseudo_inverse(D);
  const int g = c.generators();
  Eigen::VectorXd x(c.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = normal(rng);
  EXPECT_LT((c.times_inverse(x) - inv * x).norm(), 1e-10 * (inv * x).norm());
  Eigen::VectorXd hx = Eigen::VectorXd::Zero(c.size());
  hx.head(2 * g) = H.topLeftCorner(2 * g, 2 * g) * x.head(2 * g);
  EXPECT_LT((c.times_matrix(x) - hx).norm(), 1e-12 * hx.norm());
}

// A positive definite group block with one direction (not a rigid motion of the group) of
// curvature 2e-11 of the largest: its Cholesky pivots stay above 1e-10 of the largest, but the
// direction is left out of the inverse as pseudo_inverse leaves it out, not multiplied by 5e10.
TEST(OnlineSmoothedCoarse, ADirectionOfNearlyNoCurvatureIsLeftOutOfTheCoarseInverse) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  const Eigen::Index m = 12, g = 6;  // the group: blocks 0 and 1, 6 generators each
  Eigen::MatrixXd M(m, m);
  for (Eigen::Index i = 0; i < M.size(); ++i) M.data()[i] = normal(rng);
  // P S P, P = I - U U^T with U the group's rigid motions (generator j on both pieces).
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(m, g);
  for (Eigen::Index q = 0; q < m; ++q) U(q, q % g) = 1.0 / std::sqrt(2.0);
  const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(m, m) - U * U.transpose();
  const Eigen::MatrixXd S = P * (M * M.transpose() + Eigen::MatrixXd::Identity(m, m)) * P;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  // Eigenvalues 0 (x6, the rigid motions) then the six others: the smallest of those set to
  // 2e-11 of the largest.
  Eigen::VectorXd l = eig.eigenvalues();
  const double top = l(m - 1);
  l(g) = 2e-11 * top;
  const Eigen::MatrixXd& V = eig.eigenvectors();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(18, 18);
  A.topLeftCorner(m, m) = V * l.asDiagonal() * V.transpose();
  expect_kept_matrix_is_the_pseudo_inverse(A);

  const BlockLayout layout = two_groups();
  TangentCoarseSpace c(nullptr, layout, layout.poses[0], {15}, 3, 3);
  std::vector<double> packed;
  c.pack(A, packed);
  c.set_matrix(packed.data());
  Eigen::VectorXd flat = Eigen::VectorXd::Zero(c.size());
  flat.head(m) = V.col(g);
  // Kept, the inverse would be 5e10 / top along it; left out, round-off of the other inverses.
  EXPECT_LT(c.times_inverse(flat).norm(), 1e-3 / l(g + 1));
}

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
  o.newton_coarse_min_blocks = 2;
  return o;
}

int cg_iterations(const OnlineResult& r) {
  int cg = 0;
  for (const OnlineUpdate& u : r.updates) cg += u.newton_cg_iterations;
  return cg;
}

// The replay without its inter-robot measurements: three pieces that never meet. With
// `coarse`, every online step takes block Jacobi's Newton steps and CG iterations (to
// `grad_tol` in the final gradient norm) and needs no rounds.
void expect_block_jacobis_steps_before_the_robots_meet(NewtonRefineOptions::Coarse coarse,
                                                       double grad_tol) {
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
  const OnlineResult with = run_online(gen.graph.d, plan.batches, options(coarse));
  ASSERT_EQ(with.updates.size(), none.updates.size());
  int steps = 0;
  for (std::size_t k = 0; k < none.updates.size(); ++k) {
    EXPECT_EQ(with.updates[k].newton_steps, none.updates[k].newton_steps) << "step " << k;
    EXPECT_EQ(with.updates[k].newton_cg_iterations, none.updates[k].newton_cg_iterations)
        << "step " << k;
    EXPECT_EQ(with.updates[k].rounds, 0) << "step " << k;
    steps += none.updates[k].newton_steps;
  }
  EXPECT_GT(steps, 0);
  EXPECT_NEAR(with.grad_norm, none.grad_norm, grad_tol);
}

TEST(OnlineCoarse, RobotsThatHaveNotMetTakeTheSameNewtonStepsAsWithoutTheCorrection) {
  // Before the correction projected out each piece's own rigid motions, it inverted A's
  // round-off there (821 Newton steps against 310 on the first 5,010 poses of a 10,000-pose
  // grid).
  expect_block_jacobis_steps_before_the_robots_meet(NewtonRefineOptions::Coarse::kBlocks, 1e-9);
}

TEST(OnlineSmoothedCoarse, RobotsThatHaveNotMetTakeBlockJacobisNewtonSteps) {
  // Each block's pieces bend only their own block, which block Jacobi's own factor does, so no
  // coarse space is built at all: the same bits.
  expect_block_jacobis_steps_before_the_robots_meet(NewtonRefineOptions::Coarse::kSmoothed, 0.0);
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
  const OnlineResult smoothed =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kSmoothed));
  EXPECT_LT(cg_iterations(blocks), cg_iterations(none));
  EXPECT_LT(cg_iterations(smoothed), cg_iterations(blocks));
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(none.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(blocks.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(smoothed.cost, f_star, 1e-6 * f_star);
  std::printf("CG iterations: block Jacobi %d, blocks' rigid motions %d, smoothed pieces %d\n",
              cg_iterations(none), cg_iterations(blocks), cg_iterations(smoothed));
}

// Blocks 0, 1 and 2 hold one chain, block 3 a chain of its own.
BlockLayout three_linked_blocks_and_a_lone_one() {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t i = 0; i + 1 < 45; ++i) edges.emplace_back(i, i + 1);
  for (std::uint32_t i = 45; i + 1 < 60; ++i) edges.emplace_back(i, i + 1);
  std::vector<int> parts(60, 0);
  for (std::size_t i = 0; i < 60; ++i) parts[i] = static_cast<int>(i / 15);
  return make_block_layout(60, edges, parts);
}

TEST(OnlineCoarse, GroupsOfFewerLinkedBlocksThanTheMinimumAreLeftOut) {
  // Two linked blocks: in with the default minimum, out (as a lone block) with 3.
  const BlockLayout pair = two_groups();
  EXPECT_TRUE(TangentCoarseSpace(nullptr, pair, pair.poses[0], {15}, 3, 3).linked());
  const TangentCoarseSpace pair_min3(nullptr, pair, pair.poses[0], {15}, 3, 3, 3);
  EXPECT_FALSE(pair_min3.linked());
  EXPECT_EQ(pair_min3.packed_size(), 0u);
  EXPECT_TRUE(pair_min3.own().empty());
  // Three linked blocks: in with 3 (3 x 6 unknowns carried), out with 4; the lone block never.
  const BlockLayout three = three_linked_blocks_and_a_lone_one();
  const TangentCoarseSpace min3(nullptr, three, three.poses[1], {14, 30}, 3, 3, 3);
  EXPECT_TRUE(min3.linked());
  EXPECT_EQ(min3.packed_size(), 18u * 19u / 2u);
  EXPECT_FALSE(TangentCoarseSpace(nullptr, three, three.poses[1], {14, 30}, 3, 3, 4).linked());
}

TEST(OnlineCoarse, AMinimumGroupBelowTwoBlocksIsRejectedNamingTheField) {
  NewtonRefineOptions refine;
  refine.coarse_min_blocks = 1;
  EXPECT_TRUE(test::validation_names(refine, "coarse_min_blocks"));
  OnlineOptions online;
  online.newton_coarse_min_blocks = 1;
  EXPECT_TRUE(test::validation_names(online, "newton_coarse_min_blocks"));
}

TEST(OnlineSmoothedCoarse, NegativePiecesPerBlockAreRejectedNamingTheField) {
  OnlineOptions online;
  online.newton_coarse_aggregates = -1;
  EXPECT_TRUE(test::validation_names(online, "newton_coarse_aggregates"));
  NewtonRefineOptions refine;
  refine.coarse_poses_per_aggregate = -1;
  EXPECT_TRUE(test::validation_names(refine, "coarse_poses_per_aggregate"));
}

TEST(OnlineSmoothedCoarse, AutoPiecesPerBlockFollowTheBlockSizeAndReachTheBatchOptimum) {
  OnlineOptions o = options(NewtonRefineOptions::Coarse::kSmoothed);
  o.newton_coarse_aggregates = OnlineOptions::kCoarseAggregatesAuto;
  const NewtonRefineOptions refine = online_step_solver(o).refine;
  const CoarseOptions space = refine.coarse_space_options();
  EXPECT_EQ(block_aggregates(space, 500), 2);
  EXPECT_EQ(block_aggregates(space, 1000), 4);
  EXPECT_EQ(block_aggregates(space, 2000), 8);
  // A fixed count is every block's.
  o.newton_coarse_aggregates = 3;
  EXPECT_EQ(block_aggregates(online_step_solver(o).refine.coarse_space_options(), 2000), 3);

  // 150-pose blocks: one piece each with auto, eight by default; both end at the optimum, auto's
  // certified.
  const auto gen = grid(600, 4);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  o.newton_coarse_aggregates = OnlineOptions::kCoarseAggregatesAuto;
  o.certify_at_end = true;
  const OnlineResult automatic = run_online(gen.graph.d, plan.batches, o);
  ASSERT_TRUE(automatic.certified.has_value());
  EXPECT_TRUE(*automatic.certified);
  const OnlineResult eight =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kSmoothed));
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(automatic.cost, f_star, 1e-6 * f_star);
  EXPECT_NEAR(eight.cost, f_star, 1e-6 * f_star);
  EXPECT_NE(cg_iterations(automatic), cg_iterations(eight));  // the pieces did change
}

TEST(OnlineSmoothedCoarse, RobotsMetOnlyInPairsTakeBlockJacobisStepsWithAMinimumOfThree) {
  // Two robots: one group of two blocks at most, so with newton_coarse_min_blocks = 3 no
  // coarse space is built and every step is block Jacobi's, bit for bit.
  const auto gen = grid(240, 2);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  const OnlineResult none =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kNone));
  OnlineOptions o = options(NewtonRefineOptions::Coarse::kSmoothed);
  o.newton_coarse_min_blocks = 3;
  const OnlineResult min3 = run_online(gen.graph.d, plan.batches, o);
  const OnlineResult min2 =
      run_online(gen.graph.d, plan.batches, options(NewtonRefineOptions::Coarse::kSmoothed));
  ASSERT_EQ(min3.updates.size(), none.updates.size());
  for (std::size_t k = 0; k < none.updates.size(); ++k) {
    EXPECT_EQ(min3.updates[k].newton_steps, none.updates[k].newton_steps) << "step " << k;
    EXPECT_EQ(min3.updates[k].newton_cg_iterations, none.updates[k].newton_cg_iterations)
        << "step " << k;
  }
  EXPECT_EQ(min3.cost, none.cost);
  // The pair does take the correction with the default minimum (the test is not vacuous).
  EXPECT_NE(cg_iterations(min2), cg_iterations(none));
}

TEST(OnlineSmoothedCoarse, ClosuresThatLeaveTheHessianIndefiniteAreSolvedByNewtonStepsAlone) {
  // sphere2500 over 5 robots: at 4.5 s the last rings' closures arrive and f jumps from ~1,350
  // to 406,647, where the Galerkin matrix of Hess f is indefinite (smallest eigenvalue -0.03 to
  // -146 against ~1e7) or nearly singular in the pieces' relative motions. Inverting it made
  // those motions short in the preconditioner's norm, each Newton step was rejected or cut
  // back, and the step ran into the 100-step cap and handed over to 130 rounds. The online
  // steps' coarse matrix is the Hessian's data part, positive semi-definite like the kept block
  // factors: the step needs no round.
  TESSERA_REQUIRE_SHARED();
  const PoseGraph g = read_g2o(test::shared_dir() + "/datasets/sphere2500.g2o");
  ReplayOptions ro;
  ro.rate = 10;
  ro.speedup = 10;
  ReplayPlan plan = plan_replay(g, robot_of_poses(g.num_poses, 5), ro);
  plan.batches.erase(std::find_if(plan.batches.begin(), plan.batches.end(),
                                  [](const StreamBatch& b) { return b.stamp > 4.5; }),
                     plan.batches.end());
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-3;
  o.step_every_s = 0.1;
  o.certify_at_end = false;
  o.newton_coarse = NewtonRefineOptions::Coarse::kSmoothed;
  const OnlineResult r = run_online(g.d, plan.batches, o);
  ASSERT_FALSE(r.updates.empty());
  const OnlineUpdate& last = r.updates.back();
  EXPECT_GT(last.total_poses, 2250u);  // the closures are in
  EXPECT_GT(last.newton_steps, 0);
  EXPECT_LT(last.newton_steps, 100);
  for (std::size_t k = 0; k < r.updates.size(); ++k)
    EXPECT_EQ(r.updates[k].rounds, 0) << "step " << k;
  EXPECT_LE(r.grad_norm, 1e-3);
}

}  // namespace
}  // namespace tessera
