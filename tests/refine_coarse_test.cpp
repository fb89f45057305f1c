// The Newton refinement's two-level preconditioner (distributed/tangent_coarse_space.hpp): the
// coarse map Phi and its adjoint agree, its vectors are tangent and the global rigid motions do
// not change f; on a chain in blocks the two-level CG needs fewer iterations than block Jacobi
// for the same refined, certified answer.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <utility>
#include <vector>

#include "distributed/tangent_coarse_space.hpp"
#include "refine_harness.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// Block `b`'s own poses and neighbour copies of a lifted point of the whole graph.
struct BlockPoint {
  BlockProblem problem;
  Eigen::MatrixXd X, Xn;
};

BlockPoint block_point(const PoseGraph& g, const BlockLayout& layout, int b,
                       const Eigen::MatrixXd& Y) {
  BlockPoint p{
      BlockProblem(g.d, layout.poses[static_cast<std::size_t>(b)], g.measurements), {}, {}};
  p.X = gather_pose_columns(Y, p.problem.owned(), g.d);
  p.Xn = gather_pose_columns(Y, p.problem.neighbors(), g.d);
  return p;
}

TEST(TangentCoarseSpace, ItsProjectionIsTheAdjointOfItsMapAndItsVectorsAreTangent) {
  const PoseGraph g = test::refine_chain(120, 5);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, parts);
  const Eigen::MatrixXd Y = lift_poses(chordal_initialization(g), g.d);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int b = 0; b < 3; ++b) {
    const BlockPoint p = block_point(g, layout, b, Y);
    const TangentCoarseSpace c(nullptr, layout, p.problem.owned(), p.problem.neighbors(), g.d, g.d);
    ASSERT_EQ(c.size(), 3 * 6);  // 3 blocks x (3 rotations + 3 translations)
    Eigen::VectorXd xi(c.size());
    for (Eigen::Index i = 0; i < xi.size(); ++i) xi(i) = normal(rng);
    Eigen::MatrixXd v = Eigen::MatrixXd::Random(p.X.rows(), p.X.cols());
    Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(p.X.rows(), p.X.cols());
    c.expand(p.X, xi, phi);
    std::vector<double> proj(static_cast<std::size_t>(c.size()), 0.0);
    c.project(p.X, v, proj.data());
    const double lhs = (v.array() * phi.array()).sum();
    const double rhs = Eigen::Map<const Eigen::VectorXd>(proj.data(), c.size()).dot(xi);
    EXPECT_NEAR(lhs, rhs, 1e-10 * std::max(1.0, std::abs(lhs))) << "block " << b;
    // Tangent: projecting onto the tangent space changes nothing.
    const Eigen::MatrixXd t = p.problem.manifold(g.d).tangent_project(p.X, phi);
    EXPECT_LT((t - phi).norm(), 1e-12 * std::max(1.0, phi.norm())) << "block " << b;
    // Only the own block and its neighbours move its poses or copies.
    for (int u : c.touched()) {
      const int piece = u / c.generators();
      EXPECT_TRUE(piece == b || layout.adjacency_index(b, piece) >= 0) << u;
    }
  }
}

TEST(TangentCoarseSpace, EachGeneratorOfAPiecesLiftIsThatUnknownsVector) {
  // The coarse matrix's columns read every generator of a piece off one lift (lift_on, then
  // apply_generator): each must be the unknown's own vector, number for number, on the own
  // poses and the neighbour copies, with the smoothed space's blended weights.
  const PoseGraph g = test::refine_chain(120, 5);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, parts);
  NewtonRefineOptions options;
  options.coarse_aggregates = 4;
  const CoarseSpace space =
      make_coarse_space(g.num_poses, g.measurements, parts, options.coarse_space_options());
  const Eigen::MatrixXd Y = lift_poses(chordal_initialization(g), g.d);
  for (int b = 0; b < 3; ++b) {
    const BlockPoint p = block_point(g, layout, b, Y);
    const TangentCoarseSpace c(&space, layout, p.problem.owned(), p.problem.neighbors(), g.d, g.d);
    ASSERT_FALSE(c.touched().empty());
    int pieces_seen = 0, last = -1;
    for (int u : c.touched()) {
      const int piece = u / c.generators();
      if (piece != last) ++pieces_seen;
      last = piece;
      Eigen::MatrixXd lift = Eigen::MatrixXd::Zero(p.X.rows() + 1, p.X.cols());
      Eigen::MatrixXd liftn = Eigen::MatrixXd::Zero(p.X.rows() + 1, p.Xn.cols());
      c.lift_on(p.X, p.Xn, piece, c.own_slots(piece), c.neighbour_slots(piece), lift, liftn);
      Eigen::MatrixXd v, vn, ev, evn;
      c.unit(p.X, p.Xn, u, v, vn);
      c.apply_generator(u % c.generators(), lift, ev);
      c.apply_generator(u % c.generators(), liftn, evn);
      EXPECT_TRUE(ev == v) << "block " << b << " unknown " << u;
      EXPECT_TRUE(evn == vn) << "block " << b << " unknown " << u;
      EXPECT_GT(v.norm() + vn.norm(), 0.0) << "block " << b << " unknown " << u;
    }
    EXPECT_GT(pieces_seen, 4) << "block " << b;  // its own pieces and some of a neighbour's
  }
}

TEST(TangentCoarseSpace, TheGlobalRigidMotionsAreOrthogonalToTheGradient) {
  // f is invariant under one rigid motion of the whole map, so every agent's share of
  // <grad f, Phi u> for a generator u on every piece sums to zero.
  const PoseGraph g = test::refine_chain(120, 6);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, parts);
  const Eigen::MatrixXd Y = lift_poses(chordal_initialization(g), g.d);
  std::vector<double> sums;
  double scale = 0.0;
  for (int b = 0; b < 3; ++b) {
    BlockPoint p = block_point(g, layout, b, Y);
    p.problem.set_neighbor_poses(p.Xn);
    const Eigen::MatrixXd egrad = p.problem.euclidean_gradient(p.X);
    const Eigen::MatrixXd grad = p.problem.riemannian_gradient(p.X, egrad);
    scale += grad.squaredNorm();
    const TangentCoarseSpace c(nullptr, layout, p.problem.owned(), p.problem.neighbors(), g.d, g.d);
    sums.resize(static_cast<std::size_t>(c.size()), 0.0);
    c.project(p.X, grad, sums.data());
  }
  const int gens = 6;
  for (int j = 0; j < gens; ++j) {
    double total = 0.0, piece_max = 0.0;
    for (int piece = 0; piece < 3; ++piece) {
      total += sums[static_cast<std::size_t>(piece * gens + j)];
      piece_max = std::max(piece_max, std::abs(sums[static_cast<std::size_t>(piece * gens + j)]));
    }
    EXPECT_LT(std::abs(total), 1e-8 * std::max(1.0, piece_max)) << "generator " << j;
  }
  EXPECT_GT(scale, 0.0);
}

DistributedOptions refined(NewtonRefineOptions::Coarse coarse) {
  DistributedOptions o;
  o.grad_norm_tol = 1.0;
  o.certify = true;
  set_refine_mode(o.refine, "newton");
  o.refine.coarse = coarse;
  // Block Jacobi against its coarse corrections (the interface solves, the default where the
  // interface fits, are exact: newton_refine_test).
  o.refine.interface_max_coordinates = 0;
  return o;
}

int cg_iterations(const DistributedResult& r) {
  int cg = 0;
  for (const auto& n : r.refines) cg += n.cg_iterations;
  return cg;
}

TEST(NewtonRefine, TheTwoLevelPreconditionerNeedsFewerCgIterationsForTheSameCertifiedOptimum) {
  // A long chain in 5 blocks: block Jacobi moves information one block boundary per CG
  // iteration; the coarse correction moves the blocks (or their smoothed pieces) at once.
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  const DistributedResult jacobi =
      solve_distributed(g, parts, refined(NewtonRefineOptions::Coarse::kNone));
  const DistributedResult blocks =
      solve_distributed(g, parts, refined(NewtonRefineOptions::Coarse::kBlocks));
  DistributedOptions additive_options = refined(NewtonRefineOptions::Coarse::kBlocks);
  additive_options.refine.coarse_balancing = false;
  const DistributedResult additive = solve_distributed(g, parts, additive_options);
  const DistributedResult smoothed =
      solve_distributed(g, parts, refined(NewtonRefineOptions::Coarse::kSmoothed));
  for (const DistributedResult* r : {&jacobi, &blocks, &additive, &smoothed}) {
    ASSERT_FALSE(r->refines.empty());
    ASSERT_TRUE(r->certified.has_value());
    EXPECT_TRUE(*r->certified);
    EXPECT_NEAR(r->relaxation_cost, jacobi.relaxation_cost, 1e-8 * jacobi.relaxation_cost);
  }
  EXPECT_EQ(jacobi.refines.front().coarse_unknowns, 0);
  EXPECT_EQ(jacobi.refines.front().coarse_assemblies, 0);
  EXPECT_EQ(blocks.refines.front().coarse_unknowns, 5 * 6);  // 3 rotations + 3 translations
  EXPECT_GE(blocks.refines.front().coarse_assemblies, 1);
  EXPECT_GE(smoothed.refines.front().coarse_unknowns, 5 * 8 * 6);
  // Balancing removes the coarse space's error exactly; additive only adds a correction.
  EXPECT_LT(cg_iterations(blocks), cg_iterations(additive));
  EXPECT_LT(cg_iterations(additive), cg_iterations(jacobi));
  EXPECT_LT(cg_iterations(smoothed), cg_iterations(blocks));
  EXPECT_LT(2 * cg_iterations(smoothed), cg_iterations(jacobi));
  std::printf(
      "CG iterations: block Jacobi %d, blocks additive %d, blocks balancing %d, smoothed %d\n",
      cg_iterations(jacobi), cg_iterations(additive), cg_iterations(blocks),
      cg_iterations(smoothed));
}

TEST(NewtonRefine, EveryAgentTakesTheSameTwoLevelStepsInAnyDeliveryOrder) {
  const PoseGraph g = test::refine_chain(300, 4);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  DistributedOptions fifo = refined(NewtonRefineOptions::Coarse::kSmoothed);
  fifo.certify = false;
  const DistributedResult a = test::expect_same_refinement_in_any_delivery_order(g, parts, fifo, 5);
  ASSERT_EQ(a.refines.size(), 1u);
  EXPECT_GT(a.refines[0].coarse_assemblies, 0);
}

int coarse_assemblies(const DistributedResult& r) {
  int n = 0;
  for (const auto& s : r.refines) n += s.coarse_assemblies;
  return n;
}

TEST(NewtonRefine, ACoarseMatrixKeptForAFewStepsIsSummedLessOftenForTheSameCertifiedOptimum) {
  // The data part's matrix (positive semi-definite at any point) kept for the accepted steps
  // between sums: the preconditioner stays positive definite, so the steps still reach the
  // optimum; only Phi^T g is summed at the kept steps' points.
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  DistributedOptions every = refined(NewtonRefineOptions::Coarse::kSmoothed);
  every.refine.coarse_multipliers = false;
  DistributedOptions kept = every;
  kept.refine.coarse_keep_steps = 3;
  const DistributedResult a = solve_distributed(g, parts, every);
  const DistributedResult b = solve_distributed(g, parts, kept);
  for (const DistributedResult* r : {&a, &b}) {
    ASSERT_FALSE(r->refines.empty());
    ASSERT_TRUE(r->certified.has_value());
    EXPECT_TRUE(*r->certified);
  }
  EXPECT_NEAR(b.relaxation_cost, a.relaxation_cost, 1e-8 * a.relaxation_cost);
  EXPECT_GT(coarse_assemblies(b), 0);
  EXPECT_LT(coarse_assemblies(b), coarse_assemblies(a));
}

TEST(NewtonRefine, EveryAgentTakesTheSameStepsWithAKeptCoarseMatrixInAnyDeliveryOrder) {
  const PoseGraph g = test::refine_chain(300, 4);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  DistributedOptions fifo = refined(NewtonRefineOptions::Coarse::kSmoothed);
  fifo.certify = false;
  fifo.refine.coarse_multipliers = false;
  fifo.refine.coarse_keep_steps = 2;
  const DistributedResult a = test::expect_same_refinement_in_any_delivery_order(g, parts, fifo, 5);
  ASSERT_EQ(a.refines.size(), 1u);
  EXPECT_GT(a.refines[0].coarse_assemblies, 0);
}

TEST(NewtonRefine, AKeptCoarseMatrixsStepTakesPhiTgFromTheAcceptedTrialsSum) {
  // The step after an accepted trial keeps the matrix: Phi^T g at its point rode in the trial's
  // sum (the trial point is the new point), so it sends no coarse sum of its own. Each point
  // gets Phi^T g once, by a coarse sum or by the trial's, and a summed matrix serves at most
  // coarse_keep_steps - 1 carried steps.
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  DistributedOptions kept = refined(NewtonRefineOptions::Coarse::kSmoothed);
  kept.refine.coarse_multipliers = false;
  kept.refine.coarse_keep_steps = 3;
  const DistributedResult r = solve_distributed(g, parts, kept);
  ASSERT_FALSE(r.refines.empty());
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(*r.certified);
  int carried = 0;
  for (const NewtonRefineResult& s : r.refines) {
    carried += s.coarse_gradients_carried;
    EXPECT_LE(s.coarse_assemblies + s.coarse_gradients_carried, s.accepted_steps + 1);
    EXPECT_LE(s.coarse_gradients_carried, 2 * s.coarse_assemblies);
  }
  EXPECT_GT(carried, 0);
}

TEST(NewtonRefineOptions, TheCoarseSpaceOptionsAreCheckedByName) {
  NewtonRefineOptions o;
  EXPECT_EQ(test::validation_message(o), "");
  o.coarse_aggregates = 0;
  EXPECT_TRUE(test::validation_names(o, "coarse_aggregates"));
  o = {};
  o.coarse_smoothing_steps = 9;
  EXPECT_TRUE(test::validation_names(o, "coarse_smoothing_steps"));
  o = {};
  o.coarse_smoothing_steps = -1;
  EXPECT_TRUE(test::validation_names(o, "coarse_smoothing_steps"));
}

TEST(TangentCoarseSpace, APieceLinkedToNoOtherHasItsRigidMotionsLeftOutOfTheInverse) {
  // Two chains that share no measurement (robots that have not met): blocks 0 and 1 split the
  // first, block 2 holds the second. Each chain's rigid motion leaves f unchanged, so A's
  // entries there are round-off (or of the gradient's order away from a critical point); the
  // pseudo-inverse must not invert them whatever they are. Here A is any symmetric positive
  // definite matrix: block 2's rows and columns of A^+ and the common motion of blocks 0 and 1
  // must come out zero, the relative motion of blocks 0 and 1 inverted.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t i = 0; i + 1 < 30; ++i) edges.emplace_back(i, i + 1);
  for (std::uint32_t i = 30; i + 1 < 45; ++i) edges.emplace_back(i, i + 1);
  std::vector<int> parts(45, 0);
  for (std::size_t i = 15; i < 45; ++i) parts[i] = i < 30 ? 1 : 2;
  const BlockLayout layout = make_block_layout(45, edges, parts);
  const TangentCoarseSpace c(nullptr, layout, layout.poses[0], {15}, 3, 3);
  EXPECT_EQ(c.groups(), 2);
  EXPECT_EQ(c.group_of(0), c.group_of(1));
  EXPECT_NE(c.group_of(0), c.group_of(2));
  EXPECT_TRUE(c.linked());
  // Block 2's agent assembles nothing: its piece's motions are all gauge.
  EXPECT_TRUE(TangentCoarseSpace(nullptr, layout, layout.poses[2], {}, 3, 3).touched().empty());
  // Three chains that never meet: no correction at all.
  const BlockLayout apart = make_block_layout(
      45, std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 1}, {15, 16}, {30, 31}}, parts);
  EXPECT_FALSE(TangentCoarseSpace(nullptr, apart, apart.poses[0], {}, 3, 3).linked());
  EXPECT_EQ(c.touched().size(), 2u * static_cast<std::size_t>(c.generators()));
  const int g = c.generators();
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd M(c.size(), c.size());
  for (Eigen::Index i = 0; i < M.size(); ++i) M.data()[i] = normal(rng);
  const Eigen::MatrixXd A = M * M.transpose() + Eigen::MatrixXd::Identity(c.size(), c.size());
  const Eigen::MatrixXd inv = c.pseudo_inverse(A);
  const double scale = inv.norm();
  EXPECT_LT(inv.middleRows(2 * g, g).norm(), 1e-12 * scale);
  EXPECT_LT(inv.middleCols(2 * g, g).norm(), 1e-12 * scale);
  for (int j = 0; j < g; ++j) {
    Eigen::VectorXd common = Eigen::VectorXd::Zero(c.size()), relative = common;
    common(j) = common(g + j) = 1.0;
    relative(j) = 1.0;
    relative(g + j) = -1.0;
    EXPECT_LT((inv * common).norm(), 1e-12 * scale) << "generator " << j;
    EXPECT_GT((inv * relative).norm(), 1e-6 * scale) << "generator " << j;
  }
}

}  // namespace
}  // namespace tessera
