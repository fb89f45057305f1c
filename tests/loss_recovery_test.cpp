// A distributed solve that loses an agent for good at some round and continues with the
// survivors, from their current iterate and the lost agent's (stale) replica, reaches the
// centralized optimum, and its final estimate holds every pose.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tessera/distributed/loss_recovery.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "random_graph.hpp"

namespace tessera {
namespace {

// Odometry composition: a start far from the optimum, so the rounds before the loss matter.
std::vector<Pose> odometry_start(const PoseGraph& g) {
  std::vector<Pose> p(g.num_poses);
  p[0] = Pose{Eigen::MatrixXd::Identity(g.d, g.d), Eigen::VectorXd::Zero(g.d)};
  std::vector<bool> done(g.num_poses, false);
  done[0] = true;
  for (std::size_t v = 0; v + 1 < g.num_poses; ++v)
    for (const Measurement& m : g.measurements)
      if (m.i == v && m.j == v + 1) {
        p[v + 1] = Pose{p[v].R * m.R, p[v].t + p[v].R * m.t};
        done[v + 1] = true;
        break;
      }
  for (std::size_t v = 0; v < g.num_poses; ++v)
    if (!done[v]) p[v] = g.initial[v];
  return p;
}

struct Fixture {
  PoseGraph graph;
  std::vector<int> owner;
  double fstar = 0;
};

Fixture make_fixture() {
  test::RandomGraphSpec spec;
  spec.d = 3;
  spec.poses = 60;
  spec.loop_closures = 30;
  spec.seed = 5;
  Fixture f;
  f.graph = test::random_pose_graph(spec);
  PartitionOptions po;
  po.parts = 5;
  f.owner = partition_graph(graph_structure_from_pose_graph(f.graph), po).assignment;
  f.fstar = solve_centralized(f.graph).cost;
  return f;
}

DistributedOptions converge_options() {
  DistributedOptions o;
  o.grad_norm_tol = 1e-4;  // well past 1e-6 relative in cost (see distributed_solver_test)
  o.max_rounds = 20000;
  return o;
}

TEST(LossRecovery, EachAgentLostWithStaleReplicaStillReachesOptimum) {
  const Fixture f = make_fixture();
  const std::vector<Pose> start = odometry_start(f.graph);
  DistributedOptions before = converge_options();
  const int k = 12, staleness = 6;
  before.max_rounds = k;
  const DistributedResult at_k = solve_distributed(f.graph, f.owner, before, start);
  before.max_rounds = k - staleness;
  const DistributedResult replica = solve_distributed(f.graph, f.owner, before, start);
  ASSERT_EQ(at_k.rounds, k);
  ASSERT_GT(at_k.grad_norm, 100 * converge_options().grad_norm_tol)
      << "the loss must happen mid-run";
  for (int j = 0; j < 5; ++j) {
    const LossRecoveryResult r =
        continue_after_loss(f.graph, f.owner, 5, {j}, at_k.X, replica.X, converge_options());
    EXPECT_EQ(r.run.agents, 4);
    EXPECT_EQ(r.run.stop_reason, "grad_norm") << "agent " << j;
    ASSERT_EQ(r.run.poses.size(), f.graph.num_poses);  // no pose lost
    EXPECT_LE(std::abs(r.run.cost - f.fstar), 1e-6 * f.fstar)
        << "agent " << j << " lost: " << r.run.cost << " vs f* " << f.fstar;
    // The survivors started from their own iterate and the replica's columns.
    const Eigen::Index w = f.graph.d + 1;
    for (std::size_t v = 0; v < f.graph.num_poses; ++v) {
      const Eigen::MatrixXd& src = f.owner[v] == j ? replica.X : at_k.X;
      EXPECT_EQ(r.start.middleCols(w * static_cast<Eigen::Index>(v), w),
                src.middleCols(w * static_cast<Eigen::Index>(v), w));
    }
  }
}

TEST(LossRecovery, TwoAgentsLostAtOnce) {
  const Fixture f = make_fixture();
  DistributedOptions before = converge_options();
  before.max_rounds = 15;
  const DistributedResult at_k =
      solve_distributed(f.graph, f.owner, before, odometry_start(f.graph));
  const LossRecoveryResult r =
      continue_after_loss(f.graph, f.owner, 5, {0, 3}, at_k.X, at_k.X, converge_options());
  EXPECT_EQ(r.run.agents, 3);
  EXPECT_EQ(r.repartition.survivors, (std::vector<int>{1, 2, 4}));
  EXPECT_LE(std::abs(r.run.cost - f.fstar), 1e-6 * f.fstar);
}

TEST(LossRecovery, ShapeMismatchIsAnInputError) {
  const Fixture f = make_fixture();
  const Eigen::MatrixXd X = Eigen::MatrixXd::Zero(5, 4 * 60);
  EXPECT_THROW(continue_after_loss(f.graph, f.owner, 5, {1}, X, Eigen::MatrixXd::Zero(5, 8),
                                   converge_options()),
               InputError);
  EXPECT_THROW(solve_distributed_from_lifted(f.graph, f.owner, converge_options(),
                                             Eigen::MatrixXd::Zero(4, 4 * 60)),
               InputError);
}

// A loss during the Newton refinement or the certificate: the survivors hold no snapshot of those
// stages, so they start again from their last round's iterate and the replica (as over DDS,
// tests/dds_stage_loss_test.cpp) and run the certified sequence again: certified at f*.
TEST(LossRecovery, SurvivorsOfALossAfterTheRoundsRunTheCertifiedSequenceAgainToTheOptimum) {
  const Fixture f = make_fixture();
  DistributedOptions certified = converge_options();
  certified.certify = true;
  set_refine_mode(certified.refine, "newton");
  const DistributedResult undisturbed =
      solve_distributed(f.graph, f.owner, certified, odometry_start(f.graph));
  ASSERT_TRUE(undisturbed.certified.value_or(false));
  ASSERT_FALSE(undisturbed.refines.empty()) << "the undisturbed run refines";
  // The last round before the refinement, and a replica 6 rounds older.
  DistributedOptions before = converge_options();
  before.max_rounds = undisturbed.rounds;
  const DistributedResult last_round =
      solve_distributed(f.graph, f.owner, before, odometry_start(f.graph));
  before.max_rounds = std::max(1, undisturbed.rounds - 6);
  const DistributedResult replica =
      solve_distributed(f.graph, f.owner, before, odometry_start(f.graph));
  const LossRecoveryResult r =
      continue_after_loss(f.graph, f.owner, 5, {2}, last_round.X, replica.X, certified);
  EXPECT_EQ(r.run.agents, 4);
  EXPECT_TRUE(r.run.certified.value_or(false));
  ASSERT_EQ(r.run.poses.size(), f.graph.num_poses);
  EXPECT_LE(std::abs(r.run.cost - f.fstar), 1e-6 * f.fstar) << r.run.cost << " vs f* " << f.fstar;
  EXPECT_LE(std::abs(r.run.cost - undisturbed.cost), 1e-6 * f.fstar);
}

}  // namespace
}  // namespace tessera
