// An agent's share of the smoothed coarse space (runtime/coarse_space_share.hpp): with only
// the weights of its own poses and neighbour copies kept, its coarse terms, its pieces' list
// and the blend of its poses are the same to the bit, and the space holds far fewer bytes.

#include "runtime/coarse_space_share.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_exchange.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <vector>

namespace tessera {
namespace {

TEST(CoarseSpaceShare, AnAgentReadsTheSameTermsPiecesAndBlendFromItsShare) {
  GeneratorOptions go;
  go.kind = TrajectoryKind::kGrid3d;
  go.num_poses = 600;
  go.num_robots = 6;
  go.seed = 1;
  go.rotation_noise = 0.02;
  go.translation_noise = 0.1;
  const GeneratorResult gen = generate_pose_graph(go);
  const PoseGraph& g = gen.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 6);
  CoarseOptions o;
  o.aggregates = 4;
  o.smoothing_steps = 1;
  const CoarseSpace full = make_coarse_space(g.num_poses, g.measurements, part, o);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  const int r = 5;
  // A point off the truth, so the terms are not zero.
  Eigen::MatrixXd X = lift_poses(gen.ground_truth, r);
  X += 0.01 * Eigen::MatrixXd::Random(X.rows(), X.cols());
  std::vector<Eigen::MatrixXd> motions;
  for (int a = 0; a < full.num_aggregates; ++a) {
    Eigen::MatrixXd Z = Eigen::MatrixXd::Identity(r, r + 1);
    Z.col(r).setConstant(0.01 * a);
    Z(0, 1) = 0.001 * a;
    motions.push_back(Z);
  }

  for (int a = 1; a < layout.num_blocks; ++a) {
    std::vector<Measurement> touching;
    for (const Measurement& m : g.measurements)
      if (part[m.i] == a || part[m.j] == a) touching.push_back(m);
    CoarseSpace share = full;
    agent::keep_agent_share(share, layout, a, touching);
    EXPECT_LT(share.bytes(), full.bytes() * 3 / 4) << "agent " << a;

    const BlockProblem p(g.d, layout.poses[static_cast<std::size_t>(a)], g.measurements);
    const Eigen::MatrixXd Xo = gather_pose_columns(X, p.owned(), g.d);
    const Eigen::MatrixXd Xn = gather_pose_columns(X, p.neighbors(), g.d);
    const SmoothedCoarseTerms from_full(full, a, g.d, p.owned(), p.neighbors(), touching);
    const SmoothedCoarseTerms from_share(share, a, g.d, p.owned(), p.neighbors(), touching);
    EXPECT_EQ(from_share.compute(Xo, Xn), from_full.compute(Xo, Xn)) << "agent " << a;
    EXPECT_EQ(coarse_unknowns_of(&share, layout, a), coarse_unknowns_of(&full, layout, a));

    Eigen::MatrixXd own_full = Xo, own_share = Xo, nb_full = Xn, nb_share = Xn;
    apply_blended_motions(full, motions, g.d, p.owned(), own_full);
    apply_blended_motions(share, motions, g.d, p.owned(), own_share);
    apply_blended_motions(full, motions, g.d, p.neighbors(), nb_full);
    apply_blended_motions(share, motions, g.d, p.neighbors(), nb_share);
    EXPECT_TRUE(own_share == own_full) << "agent " << a;
    EXPECT_TRUE(nb_share == nb_full) << "agent " << a;
  }
}

}  // namespace
}  // namespace tessera
