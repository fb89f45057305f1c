// Distributed certification and the distributed staircase: the agents' lambda_min(S) agrees
// with the centralized certificate, a well-behaved optimum is certified, a rank-d saddle of a
// noisy graph is detected and escaped to the certified optimum, and none of it depends on the
// message delivery order.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <tessera/certification/certificate.hpp>
#include <tessera/certification/distributed_certificate.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

#include "random_graph.hpp"

namespace tessera {
namespace {

// A noisy 2D city graph whose rank-2 (r = d) critical point reached from the odometry guess
// is a saddle: the certificate fails there.
PoseGraph saddle_graph() {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kCity;
  g.num_poses = 120;
  g.rotation_noise = 0.5;
  g.translation_noise = 0.3;
  g.seed = 1;
  return generate_pose_graph(g).graph;
}

// The random graph most tests here certify on: 60 poses, 30 loop closures, rotation noise as
// given (0.1-0.3 rad: enough for critical points that are not optima).
PoseGraph noisy_graph(int d, std::uint64_t seed, double rotation_noise) {
  test::RandomGraphSpec spec;
  spec.d = d;
  spec.poses = 60;
  spec.loop_closures = 30;
  spec.seed = seed;
  spec.rotation_noise = rotation_noise;
  return test::random_pose_graph(spec);
}

// A lifted point at rank r that is not critical (its last row bent towards the first): S is well
// defined and indefinite there.
Eigen::MatrixXd bent_point(const BlockProblem& whole, const std::vector<Pose>& initial, int r) {
  Eigen::MatrixXd X = lift_poses(initial, r);
  X.row(r - 1) = 0.3 * X.row(0);
  return whole.manifold(r).project(X);
}

// Runs only the certificate protocol of N agents on an arbitrary lifted point X.
// `update` configures the agents (their Q_BB factor cap); `too_large`, when given, receives
// each agent's block_factor_too_large().
DistributedCertificateResult certify_in_process(const PoseGraph& g, const Eigen::MatrixXd& X,
                                                const std::vector<int>& assignment,
                                                DeliveryOrder order,
                                                const BlockUpdateOptions& update = {},
                                                std::vector<bool>* too_large = nullptr,
                                                const DistributedCertificateOptions& options = {}) {
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, assignment);
  std::vector<std::unique_ptr<AgentState>> states;
  std::vector<std::unique_ptr<CertificateProtocol>> protocols;
  std::vector<AgentProcess*> agents;
  for (int b = 0; b < layout.num_blocks; ++b) {
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    states.push_back(std::make_unique<AgentState>(b, g.d, layout, g.measurements,
                                                  gather_pose_columns(X, ids, g.d), update));
    if (too_large) too_large->push_back(states.back()->block_factor_too_large());
    states.back()->Yn = gather_pose_columns(X, states.back()->problem().neighbors(), g.d);
    protocols.push_back(std::make_unique<CertificateProtocol>(*states.back(), layout, options));
    agents.push_back(protocols.back().get());
  }
  run_in_process(agents, order, 7);
  for (const auto& p : protocols) {  // every agent decided the same
    EXPECT_EQ(p->result().min_eigenvalue, protocols.front()->result().min_eigenvalue);
    EXPECT_EQ(p->result().iterations, protocols.front()->result().iterations);
  }
  return protocols.front()->result();
}

TEST(DistributedCertificate, MinimumEigenvalueMatchesCentralizedAtAnyPoint) {
  const PoseGraph g = noisy_graph(2, 4, 0.3);
  const BlockProblem whole = BlockProblem::whole_graph(2, g.num_poses, g.measurements);
  const Eigen::MatrixXd X = bent_point(whole, g.initial, 3);
  const CertificateResult central = verify_certificate(whole, X);
  ASSERT_FALSE(central.certified);
  const DistributedCertificateResult dist =
      certify_in_process(g, X, sequential_partition(g.num_poses, 4), DeliveryOrder::kFifo);
  EXPECT_TRUE(dist.converged);
  EXPECT_FALSE(dist.certified);
  EXPECT_EQ(dist.tolerance, central.tolerance);
  EXPECT_NEAR(dist.min_eigenvalue, central.min_eigenvalue, 1e-3 * std::abs(central.min_eigenvalue));
  // theta is a Rayleigh quotient: never below the true minimum (up to round-off).
  EXPECT_GE(dist.min_eigenvalue, central.min_eigenvalue - 1e-9 * std::abs(central.min_eigenvalue));
}

// An agent whose Q_BB factor is too large preconditions the certificate pose by pose (the
// (d+1) x (d+1) diagonal blocks of its shifted S_BB) instead of factoring its whole block: the
// same minimum eigenvalue, memory linear in the block.
TEST(DistributedCertificate, PoseWisePreconditionerAboveTheFactorCapFindsTheSameEigenvalue) {
  const PoseGraph g = noisy_graph(3, 5, 0.3);
  const BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  const Eigen::MatrixXd X = bent_point(whole, g.initial, 4);
  const CertificateResult central = verify_certificate(whole, X);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  BlockUpdateOptions capped;
  capped.max_factor_entries = 1;
  std::vector<bool> too_large;
  const DistributedCertificateResult pose_wise =
      certify_in_process(g, X, parts, DeliveryOrder::kFifo, capped, &too_large);
  EXPECT_EQ(too_large, std::vector<bool>(3, true));
  std::vector<bool> exact_too_large;
  const DistributedCertificateResult exact =
      certify_in_process(g, X, parts, DeliveryOrder::kFifo, {}, &exact_too_large);
  EXPECT_EQ(exact_too_large, std::vector<bool>(3, false));
  EXPECT_TRUE(pose_wise.converged);
  EXPECT_EQ(pose_wise.certified, central.certified);
  EXPECT_NEAR(pose_wise.min_eigenvalue, central.min_eigenvalue,
              1e-3 * std::max(1.0, std::abs(central.min_eigenvalue)));
  EXPECT_NEAR(pose_wise.min_eigenvalue, exact.min_eigenvalue,
              1e-3 * std::max(1.0, std::abs(exact.min_eigenvalue)));
  // A weaker preconditioner: at least as many iterations as the block factor's.
  EXPECT_GE(pose_wise.iterations, exact.iterations);
}

TEST(DistributedCertificate, CertifiesTheOptimumOfAWellBehavedGraph) {
  test::RandomGraphSpec spec;
  spec.d = 3;
  spec.poses = 50;
  spec.loop_closures = 25;
  spec.seed = 2;
  const PoseGraph g = test::random_pose_graph(spec);
  DistributedOptions opt;
  opt.certify = true;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 3), opt);
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(*r.certified);
  EXPECT_EQ(r.final_rank, 5);
  EXPECT_TRUE(r.escapes.empty());
  EXPECT_GT(r.certificate_rounds, 0);
  EXPECT_GT(r.certificate_bytes, 0u);
  // Certified at the solver's own tolerance: no refinement was needed.
  EXPECT_LE(r.grad_norm, opt.grad_norm_tol);
  EXPECT_EQ(r.refine_rounds, 0);
  EXPECT_EQ(r.certificates.size(), 1u);
  // Same verdict and eigenvalue (within eta) as the centralized certificate at the same point.
  const BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  const CertificateResult central = verify_certificate(whole, r.X);
  EXPECT_TRUE(central.certified);
  EXPECT_NEAR(r.min_eigenvalue, central.min_eigenvalue, central.tolerance);
}

TEST(DistributedCertificate, OffByDefaultSendsOnlyTheSolversMessages) {
  test::RandomGraphSpec spec;
  spec.d = 2;
  spec.poses = 40;
  spec.seed = 3;
  const PoseGraph g = test::random_pose_graph(spec);
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 3), {});
  EXPECT_FALSE(r.certified.has_value());
  EXPECT_EQ(r.certificate_rounds, 0);
  EXPECT_EQ(r.certificate_bytes, 0u);
  EXPECT_EQ(r.final_rank, 5);
}

DistributedOptions saddle_options(DeliveryOrder order) {
  DistributedOptions opt;
  opt.rank = 2;  // r = d: the staircase must climb
  opt.initialization = DistributedInit::kChordal;
  opt.certify = true;
  opt.delivery = order;
  opt.delivery_seed = 11;
  return opt;
}

TEST(DistributedStaircase, RankDSaddleEscapesToTheCertifiedOptimum) {
  const PoseGraph g = saddle_graph();
  const std::vector<Pose> start = g.initial;  // odometry: far from the optimum
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 4),
                                                saddle_options(DeliveryOrder::kFifo), start);
  ASSERT_GE(r.certificates.size(), 2u);
  const auto& first = r.certificates.front();
  EXPECT_EQ(first.rank, 2);
  EXPECT_FALSE(first.result.certified);
  EXPECT_LT(first.result.min_eigenvalue, -first.result.tolerance);
  ASSERT_FALSE(r.escapes.empty());
  EXPECT_TRUE(r.escapes.front().success);
  // The relaxation's certificate (the saddle graph's relaxation is not tight, so the rounded
  // estimate is not certified: rounding_gap_test).
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(r.certificates.back().result.certified);
  EXPECT_GT(r.final_rank, 2);
  EXPECT_EQ(r.X.rows(), r.final_rank);
  // The same optimum as the centralized certified solver (the SDP's optimum is unique in value).
  CentralizedOptions tight;
  tight.stop = CentralizedStop::kGradient;
  const CentralizedResult ref = solve_centralized(g, tight);
  ASSERT_FALSE(ref.levels.empty());
  ASSERT_TRUE(ref.levels.back().certified);
  EXPECT_EQ(r.certified, ref.certified);
  EXPECT_NEAR(r.relaxation_cost, ref.relaxation_cost, 1e-6 * ref.relaxation_cost);
  // Rank 3 is proven optimal at the solver's tolerance 0.01 by the interface test (LOBPCG alone
  // stopped at its cap there, and the rank was refined to 1e-4 first): the rounded cost is as
  // close as a point at ||grad f|| ~ 0.01 gives.
  EXPECT_NEAR(r.cost, ref.cost, 3e-5 * ref.cost);
}

// The refinement of an inconclusive certificate is by rounds to StaircaseOptions::grad_norm_tol
// when the Newton refinement is off (below: by the Newton refinement when it is on).
TEST(DistributedStaircase, InconclusiveCertificateRefinesTheSameRankBeforeEscaping) {
  const PoseGraph g = saddle_graph();
  DistributedOptions o = saddle_options(DeliveryOrder::kFifo);
  o.refine.enabled = false;  // the rounds to the refinement tolerance, as tested here
  const DistributedResult r =
      solve_distributed(g, sequential_partition(g.num_poses, 4), o, g.initial);
  // Rank 2 at the solver's tolerance: not certified, so rank 2 is refined (more solver rounds
  // at rank 2) and certified again; only that second failure leads to the escape.
  ASSERT_GE(r.certificates.size(), 3u);
  EXPECT_EQ(r.certificates[0].rank, 2);
  EXPECT_FALSE(r.certificates[0].result.certified);
  EXPECT_EQ(r.certificates[1].rank, 2);
  EXPECT_FALSE(r.certificates[1].result.certified);
  EXPECT_EQ(r.certificates[1].stage, r.certificates[0].stage + 3);  // solve, no escape between
  ASSERT_FALSE(r.escapes.empty());
  EXPECT_EQ(r.escapes.front().rank, 2);
  EXPECT_EQ(r.escapes.front().stage, r.certificates[1].stage + 1);
  EXPECT_GT(r.refine_rounds, 0);
  EXPECT_LT(r.refine_rounds, r.rounds);
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(r.certificates.back().result.certified);
}

// max_rounds is the run's round budget: a solve that runs out of it is certified once (its
// minimum eigenvalue is the reported gap), neither refined nor escaped from.
TEST(DistributedStaircase, ASolveOutOfRoundsIsCertifiedOnceAndNotContinued) {
  const PoseGraph g = saddle_graph();
  DistributedOptions opt = saddle_options(DeliveryOrder::kFifo);
  opt.max_rounds = 2;
  const DistributedResult r =
      solve_distributed(g, sequential_partition(g.num_poses, 4), opt, g.initial);
  ASSERT_EQ(r.certificates.size(), 1u);
  EXPECT_FALSE(r.certificates[0].result.certified);
  EXPECT_EQ(r.min_eigenvalue, r.certificates[0].result.min_eigenvalue);
  EXPECT_TRUE(r.escapes.empty());
  EXPECT_EQ(r.refine_rounds, 0);
  EXPECT_LE(r.rounds, 2);
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_FALSE(*r.certified);
}

// The acceptance rule at loose solve tolerances: a certificate that holds at a point that is
// not (yet) critical must also hold for the centralized certificate at that same point, with
// the same minimum eigenvalue to within eta. Refinement off, so each verdict stands as is.
// At points the Newton refinement took far below the solver's tolerance, S's null space is a
// tight cluster at the top of the shift-inverted spectrum; the centralized certificate still
// reports lambda_min (the narrow Lanczos run from X's rows once missed it there: NaN).
TEST(DistributedCertificate, TheCentralizedCertificateReportsLambdaMinAtRefinedPoints) {
  const PoseGraph g = noisy_graph(3, 5, 0.2);
  const BlockProblem whole = BlockProblem::whole_graph(g.d, g.num_poses, g.measurements);
  for (double tol : {1.0, 0.1}) {
    DistributedOptions opt;
    opt.rank = g.d;
    opt.certify = true;
    opt.grad_norm_tol = tol;
    opt.staircase.grad_norm_tol = 0;
    set_refine_mode(opt.refine, "newton");
    opt.staircase.max_rank = g.d + 1;
    const DistributedResult r =
        solve_distributed(g, sequential_partition(g.num_poses, 3), opt, g.initial);
    const CertificateResult central = verify_certificate(whole, r.X);
    SCOPED_TRACE("tol " + std::to_string(tol));
    ASSERT_TRUE(central.certified);
    EXPECT_TRUE(std::isfinite(central.min_eigenvalue));
    EXPECT_GE(central.min_eigenvalue, -central.tolerance);
  }
}

TEST(DistributedCertificate, HoldsAtALoosePointOnlyWhereTheCentralizedCertificateHolds) {
  std::vector<PoseGraph> graphs;
  for (std::uint64_t seed : {5u, 6u}) graphs.push_back(noisy_graph(seed == 5u ? 3 : 2, seed, 0.2));
  graphs.push_back(saddle_graph());
  int certified = 0, rejected = 0;
  for (const PoseGraph& g : graphs) {
    const BlockProblem whole = BlockProblem::whole_graph(g.d, g.num_poses, g.measurements);
    for (double tol : {1.0, 0.1, 0.01}) {
      DistributedOptions opt;
      opt.rank = g.d;  // from rank d, so some verdicts are negative
      opt.certify = true;
      opt.grad_norm_tol = tol;
      opt.staircase.grad_norm_tol = 0;      // no refinement: the loose verdict is final
      set_refine_mode(opt.refine, "none");  // nor the Newton one: the loose point is the test
      opt.staircase.max_rank = g.d + 1;
      const DistributedResult r =
          solve_distributed(g, sequential_partition(g.num_poses, 3), opt, g.initial);
      ASSERT_TRUE(r.certified.has_value());
      const CertificateResult central = verify_certificate(whole, r.X);
      SCOPED_TRACE("d " + std::to_string(g.d) + " tol " + std::to_string(tol));
      // The bound is proved by the same test (S + D > 0) at the same shifts: the same f_lb.
      const DistributedCertificateResult& last = r.certificates.back().result;
      if (last.bound.proved()) {
        ++certified;
        ASSERT_TRUE(central.bound.proved());
        EXPECT_NEAR(last.bound.lower_bound, central.bound.lower_bound,
                    1e-9 * std::abs(central.bound.relaxation_cost));
        EXPECT_EQ(last.certified, central.certified);
      } else {
        ++rejected;
      }
    }
  }
  EXPECT_GT(certified, 0);  // the checks above did run
  std::printf("loose-point bounds: %d proved, %d not\n", certified, rejected);
}

TEST(DistributedStaircase, DeliveryOrderDoesNotChangeTheResult) {
  const PoseGraph g = saddle_graph();
  const auto assignment = sequential_partition(g.num_poses, 4);
  const DistributedResult a =
      solve_distributed(g, assignment, saddle_options(DeliveryOrder::kFifo), g.initial);
  const DistributedResult b =
      solve_distributed(g, assignment, saddle_options(DeliveryOrder::kShuffled), g.initial);
  const DistributedResult c =
      solve_distributed(g, assignment, saddle_options(DeliveryOrder::kReversed), g.initial);
  for (const DistributedResult* o : {&b, &c}) {
    EXPECT_EQ(o->cost, a.cost);
    EXPECT_EQ(o->rounds, a.rounds);
    EXPECT_EQ(o->min_eigenvalue, a.min_eigenvalue);
    EXPECT_EQ(o->certificate_rounds, a.certificate_rounds);
    EXPECT_EQ(o->escape_rounds, a.escape_rounds);
    EXPECT_EQ(o->final_rank, a.final_rank);
    EXPECT_EQ(o->certificate_bytes, a.certificate_bytes);
  }
}

}  // namespace

// The interface test (substructuring, interface_schur.hpp) is a factorization of S + eta I
// like the centralized certificate's: the same verdict at optima, at saddles and at arbitrary
// points, in 2D and 3D, keeping both endpoints of each cut measurement or one (the other
// eliminated in its block), on contiguous blocks and on a scattered partition where most
// poses are cut and many touch several blocks; LOBPCG then finds the escape direction where
// it fails.
TEST(DistributedCertificate, InterfaceTestGivesTheCentralizedFactorizationsVerdict) {
  int certified = 0, rejected = 0;
  for (int d : {2, 3}) {
    const PoseGraph g = noisy_graph(d, 7 + static_cast<std::uint64_t>(d), 0.2);
    const BlockProblem whole = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
    CentralizedOptions tight;
    tight.stop = CentralizedStop::kGradient;
    const CentralizedResult opt = solve_centralized(g, tight);
    ASSERT_TRUE(opt.certified.value_or(false));
    const std::vector<Eigen::MatrixXd> points{opt.X, bent_point(whole, g.initial, 3)};
    std::vector<std::vector<int>> partitions{sequential_partition(g.num_poses, 1),
                                             sequential_partition(g.num_poses, 3)};
    std::vector<int> scattered(g.num_poses);
    for (std::size_t i = 0; i < g.num_poses; ++i) scattered[i] = static_cast<int>((i * 7) % 4);
    partitions.push_back(scattered);
    for (const Eigen::MatrixXd& X : points) {
      const CertificateResult central = verify_certificate(whole, X);
      for (const auto& parts : partitions)
        for (bool one_side : {true, false}) {
          DistributedCertificateOptions options;
          options.interface_max_coordinates = 100000;
          options.interface_one_side = one_side;
          const DistributedCertificateResult dist =
              certify_in_process(g, X, parts, DeliveryOrder::kFifo, {}, nullptr, options);
          const int blocks = *std::max_element(parts.begin(), parts.end()) + 1;
          EXPECT_TRUE(dist.interface_test);
          EXPECT_EQ(dist.certified, central.certified)
              << "d " << d << " blocks " << blocks << " one side " << one_side;
          EXPECT_EQ(dist.tolerance, central.tolerance);
          if (central.certified) {
            ++certified;
            EXPECT_NEAR(dist.min_eigenvalue, central.min_eigenvalue, central.tolerance);
          } else {
            ++rejected;  // LOBPCG ran for the eigenvector: a proof of the failure too
            EXPECT_LT(dist.min_eigenvalue, -dist.tolerance);
            EXPECT_GT(dist.iterations, 1);
          }
        }
    }
  }
  EXPECT_GT(certified, 0);
  EXPECT_GT(rejected, 0);
}

// Above interface_max_coordinates the certificate is LOBPCG alone, as without the test.
TEST(DistributedCertificate, AboveTheInterfaceCapOnlyLobpcgRuns) {
  test::RandomGraphSpec spec;
  spec.d = 2;
  spec.poses = 50;
  spec.loop_closures = 25;
  spec.seed = 2;
  const PoseGraph g = test::random_pose_graph(spec);
  DistributedOptions opt;
  opt.certify = true;
  const auto parts = sequential_partition(g.num_poses, 3);
  const DistributedResult with = solve_distributed(g, parts, opt);
  opt.staircase.certificate.interface_max_coordinates = 3;  // less than one pose
  const DistributedResult without = solve_distributed(g, parts, opt);
  ASSERT_EQ(with.certificates.size(), 1u);
  ASSERT_EQ(without.certificates.size(), 1u);
  EXPECT_TRUE(with.certificates[0].result.interface_test);
  EXPECT_FALSE(without.certificates[0].result.interface_test);
  EXPECT_TRUE(*with.certified);
  EXPECT_TRUE(*without.certified);
  EXPECT_EQ(with.certificate_bound.method, CertificateMethod::kExact);
  // LOBPCG alone estimates lambda_min at a critical point and proves no bound.
  EXPECT_EQ(without.certificate_bound.method, CertificateMethod::kLobpcg);
  EXPECT_FALSE(without.certificate_bound.proved());
  EXPECT_LT(with.certificate_rounds, without.certificate_rounds);
  EXPECT_NEAR(with.min_eigenvalue, without.min_eigenvalue, with.certificates[0].result.tolerance);
  EXPECT_EQ(with.cost, without.cost);  // the certificate does not move the point
}

namespace {

// The lifted optimum of a generated graph (certified, f* = its relaxation cost, to round-off)
// and a point near it that is not first-order critical: the optimum's rotations turned by a
// small random step. There lambda_min(S) is only slightly negative (S + eta I still factors),
// but f(Y) is well above f*: only the bound can tell.
struct OptimumAndNearby {
  PoseGraph graph;
  CentralizedResult optimum;
  Eigen::MatrixXd nearby;
};

OptimumAndNearby optimum_and_nearby(int d, std::uint64_t seed) {
  OptimumAndNearby o;
  o.graph = noisy_graph(d, seed, 0.1);
  CentralizedOptions tight;
  tight.stop = CentralizedStop::kGradient;
  o.optimum = solve_centralized(o.graph, tight);
  const BlockProblem whole = BlockProblem::whole_graph(d, o.graph.num_poses, o.graph.measurements);
  Eigen::MatrixXd X = o.optimum.X;
  std::uint64_t z = seed;
  for (Eigen::Index c = 0; c < X.cols(); ++c)
    for (Eigen::Index r = 0; r < X.rows(); ++r) {
      z = z * 6364136223846793005ull + 1442695040888963407ull;
      X(r, c) += 2e-4 * (static_cast<double>(z >> 11) * 0x1.0p-53 - 0.5);
    }
  o.nearby = whole.manifold(static_cast<int>(X.rows())).project(X);
  return o;
}

double relaxation_cost(const BlockProblem& whole, const Eigen::MatrixXd& X) {
  return (X * whole.data_matrix()).cwiseProduct(X).sum();
}

}  // namespace

// Weak duality at any point: the bound is proved below the optimum, and a point that is not
// critical is not certified even where lambda_min(S) >= -eta (the old rule's "optimal").
TEST(CertificateBound, ANonCriticalPointIsNotCertifiedAndItsLowerBoundIsBelowTheOptimum) {
  for (int d : {2, 3}) {
    SCOPED_TRACE("d " + std::to_string(d));
    const OptimumAndNearby o = optimum_and_nearby(d, 21 + static_cast<std::uint64_t>(d));
    ASSERT_TRUE(o.optimum.certified.value_or(false));
    const double f_star = o.optimum.relaxation_cost;  // >= the SDP's optimum
    const BlockProblem whole =
        BlockProblem::whole_graph(d, o.graph.num_poses, o.graph.measurements);
    const double f = relaxation_cost(whole, o.nearby);
    ASSERT_GT(f - f_star, 1e-5 * f_star) << "the point should be clearly suboptimal";
    const CertificateResult c = verify_certificate(whole, o.nearby);
    EXPECT_FALSE(c.certified);
    EXPECT_TRUE(c.psd_within_tolerance);  // what alone used to certify
    ASSERT_TRUE(c.bound.proved());
    EXPECT_LE(c.bound.lower_bound, f_star);
    EXPECT_NEAR(c.bound.relaxation_cost, f, 1e-12 * f);
    EXPECT_GT(c.bound.gradient_norm, 0.0);
    std::printf("d %d: f - f* = %.3g, f - f_lb = %.3g, lambda_min(S) = %.3g (eta %.3g)\n", d,
                f - f_star, f - c.bound.lower_bound, c.min_eigenvalue, c.tolerance);
  }
}

TEST(CertificateBound, AtTheOptimumTheBoundIsTight) {
  for (int d : {2, 3}) {
    SCOPED_TRACE("d " + std::to_string(d));
    const OptimumAndNearby o = optimum_and_nearby(d, 31 + static_cast<std::uint64_t>(d));
    const BlockProblem whole =
        BlockProblem::whole_graph(d, o.graph.num_poses, o.graph.measurements);
    const CertificateResult c = verify_certificate(whole, o.optimum.X);
    EXPECT_TRUE(c.certified);
    ASSERT_TRUE(c.bound.proved());
    const double f_star = o.optimum.relaxation_cost;
    EXPECT_LE(c.bound.lower_bound, f_star);
    EXPECT_LE(c.bound.relative_suboptimality(f_star), CertificateOptions{}.suboptimality_tolerance);
    EXPECT_LE(c.bound.gradient_norm, 1e-4 * std::max(1.0, f_star));
  }
}

// The agents prove the same bound as the centralized factorization, at the optimum and near it.
TEST(CertificateBound, DistributedBoundIsTheCentralizedOne) {
  const OptimumAndNearby o = optimum_and_nearby(3, 41);
  const PoseGraph& g = o.graph;
  const BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  DistributedCertificateOptions options;
  options.interface_max_coordinates = 100000;
  const auto parts = sequential_partition(g.num_poses, 3);
  const CertificateResult central = verify_certificate(whole, o.optimum.X);
  const DistributedCertificateResult dist =
      certify_in_process(g, o.optimum.X, parts, DeliveryOrder::kFifo, {}, nullptr, options);
  EXPECT_TRUE(central.certified);
  EXPECT_TRUE(dist.certified);
  ASSERT_TRUE(dist.bound.proved());
  EXPECT_NEAR(dist.bound.shift, central.bound.shift, 1e-9 * central.bound.shift);
  const double f = central.bound.relaxation_cost;
  EXPECT_NEAR(dist.bound.lower_bound, central.bound.lower_bound, 1e-10 * f);
  EXPECT_NEAR(dist.bound.relaxation_cost, f, 1e-10 * f);
  EXPECT_NEAR(dist.bound.gradient_norm, central.bound.gradient_norm, 1e-6 * f);

  const DistributedCertificateResult near =
      certify_in_process(g, o.nearby, parts, DeliveryOrder::kFifo, {}, nullptr, options);
  EXPECT_FALSE(near.certified);
  if (near.bound.proved()) {
    EXPECT_LE(near.bound.lower_bound, o.optimum.relaxation_cost);
  }
  // Without the interface test nothing proves a bound: LOBPCG's estimate certifies the
  // optimum (a critical point), not the point near it, whose lambda_min(S) >= -eta too.
  options.interface_max_coordinates = 0;
  const DistributedCertificateResult lobpcg =
      certify_in_process(g, o.optimum.X, parts, DeliveryOrder::kFifo, {}, nullptr, options);
  EXPECT_FALSE(lobpcg.interface_test);
  EXPECT_EQ(lobpcg.bound.method, CertificateMethod::kLobpcg);
  EXPECT_FALSE(lobpcg.bound.proved());
  EXPECT_TRUE(lobpcg.certified);
  EXPECT_NEAR(lobpcg.bound.relaxation_cost, f, 1e-10 * f);
  const DistributedCertificateResult lobpcg_near =
      certify_in_process(g, o.nearby, parts, DeliveryOrder::kFifo, {}, nullptr, options);
  EXPECT_TRUE(lobpcg_near.psd_within_tolerance);
  EXPECT_FALSE(lobpcg_near.certified);
}

// The proof's ladder jumps from t = 1 to the largest t whose bound still certifies: there the
// bound spends 0.99 of the tolerance, and any larger t is over it.
TEST(CertificateBound, TheLargestCertifyingMultiplierSpendsTheToleranceAndNoMore) {
  const double f = 717.126, trace_lambda = 717.104, s0 = 4.157e-7, weight_sum = 3.95e-7;
  const std::size_t n = 5750;
  const int d = 3;
  const double tol = kDefaultSuboptimalityTolerance;
  const double t = largest_certifying_multiplier(f, trace_lambda, s0, weight_sum, n, d, tol);
  ASSERT_GT(t, 1.0);
  const auto bound_at = [&](double m) {
    return make_dual_bound(f, trace_lambda, 0.0, m * (s0 * static_cast<double>(n) + weight_sum), n,
                           d);
  };
  EXPECT_NEAR(bound_at(t).relative_suboptimality(f), kCertifyingMargin * tol, 1e-12);
  EXPECT_TRUE(bound_certifies(bound_at(t), tol));
  EXPECT_FALSE(bound_certifies(bound_at(1.02 * t), tol));
  // f(Y) - tr(Lambda) (the translations' share of the gradient) over the tolerance: no t.
  EXPECT_LE(largest_certifying_multiplier(f, f - 2 * tol * f, s0, weight_sum, n, d, tol), 0.0);
}

// Solver iterates ever closer to the optimum (IRBCD stopped at gradient norms 0.3 down to
// 1e-3): one that is certified is within the tolerance of the optimum (weak duality), the
// agents' interface test gives the centralized verdict, and some are certified only by the
// ladder's second test (the largest certifying t), which a ladder of factors of 3 can step over.
TEST(CertificateBound, AnIterateShortOfCriticalIsCertifiedOnlyWithinTheTolerance) {
  GeneratorOptions gen;
  gen.kind = TrajectoryKind::kGrid3d;
  gen.num_poses = 343;
  gen.seed = 2;
  const PoseGraph g = generate_pose_graph(gen).graph;
  const BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  CentralizedOptions tight;
  tight.stop = CentralizedStop::kGradient;
  const double f_star = solve_centralized(g, tight).relaxation_cost;
  const double tol = kDefaultSuboptimalityTolerance;
  const auto parts = sequential_partition(g.num_poses, 3);
  DistributedCertificateOptions options;
  options.interface_max_coordinates = 100000;
  int certified = 0, by_the_second_test = 0, not_certified = 0;
  for (double grad_tol : {0.3, 0.1, 0.03, 0.01, 0.003, 0.001}) {
    SCOPED_TRACE("grad_tol " + std::to_string(grad_tol));
    DistributedOptions o;
    o.grad_norm_tol = grad_tol;
    o.certify = false;
    o.refine.enabled = false;
    const DistributedResult r = solve_distributed(g, parts, o, g.initial);
    const Eigen::MatrixXd& Y = r.X;
    const double f = relaxation_cost(whole, Y);
    const CertificateResult c = verify_certificate(whole, Y);
    const DistributedCertificateResult dist =
        certify_in_process(g, Y, parts, DeliveryOrder::kFifo, {}, nullptr, options);
    std::printf("|grad f| %.2g: f - f* = %.3g (%.2g relative), certified %d after %d proof tests\n",
                r.trace.empty() ? -1.0 : r.trace.back().grad_norm, f - f_star,
                (f - f_star) / std::max(1.0, f), int(c.certified), c.proof_factorizations);
    EXPECT_EQ(dist.certified, c.certified);
    if (c.certified) {
      ++certified;
      EXPECT_LE(f - f_star, tol * std::max(1.0, std::abs(f)));
      EXPECT_LE(c.bound.lower_bound, f_star);
      if (c.proof_factorizations == 2) ++by_the_second_test;
    } else {
      ++not_certified;
    }
  }
  EXPECT_GT(certified, 0);
  EXPECT_GT(by_the_second_test, 0);
  EXPECT_GT(not_certified, 0);
}

// With the Newton refinement on (the default), an inconclusive certificate's refinement is
// the Newton refinement's: the refining stage's rounds stop at once (the point is at the
// solver's tolerance already), a Newton refinement runs there, and only a failure at the
// refined point leads to the escape.
TEST(DistributedStaircase, InconclusiveCertificateIsRefinedByNewtonWithoutMoreRounds) {
  const PoseGraph g = saddle_graph();
  DistributedOptions o = saddle_options(DeliveryOrder::kFifo);
  o.refine.auto_interface_grad_tol = 0;  // the rounds to the solver's tolerance first
  const DistributedResult r =
      solve_distributed(g, sequential_partition(g.num_poses, 4), o, g.initial);
  ASSERT_GE(r.certificates.size(), 3u);
  EXPECT_EQ(r.certificates[0].rank, 2);
  EXPECT_FALSE(r.certificates[0].result.certified);
  EXPECT_EQ(r.certificates[1].rank, 2);
  EXPECT_EQ(r.certificates[1].stage, r.certificates[0].stage + 3);  // solve, no escape between
  EXPECT_EQ(r.refine_rounds, 0);
  EXPECT_FALSE(r.refines.empty());
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(r.certificates.back().result.certified);
}

}  // namespace tessera
