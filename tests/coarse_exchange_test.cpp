// The gathered coarse exchange (coarse_exchange.hpp): each agent receives from the solver agent
// exactly the motions the all-to-all solve computed for the poses it holds, so two-level rounds
// give the all-to-all iterates bit for bit, under any delivery, with fewer bytes.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/coarse_exchange.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/lifting.hpp>
#include <vector>

#include "round_agents.hpp"

namespace tessera {
namespace {

struct Grid {
  PoseGraph graph;
  std::vector<Pose> truth;
};

Grid grid(std::size_t poses) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = poses;
  o.num_robots = 4;
  o.seed = 1;
  o.rotation_noise = 0.01;
  o.translation_noise = 0.05;
  GeneratorResult r = generate_pose_graph(o);
  return {std::move(r.graph), std::move(r.ground_truth)};
}

// The truth bent smoothly about the z axis (the slow error the coarse space targets).
Eigen::MatrixXd bent(const std::vector<Pose>& truth, int r) {
  std::vector<Pose> b = truth;
  for (Pose& p : b) {
    const double a = 0.05 * p.t(0);
    Eigen::Matrix3d Rz;
    Rz << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
    p.R = Rz * p.R;
    p.t = Rz * p.t;
  }
  return lift_poses(b, r);
}

// One agent per block of `part`, at X, over `space` (null: the block space).
std::vector<std::unique_ptr<AgentState>> agents(const PoseGraph& g, const BlockLayout& layout,
                                                const std::shared_ptr<const CoarseSpace>& space,
                                                const Eigen::MatrixXd& X) {
  std::vector<std::unique_ptr<AgentState>> out;
  for (int a = 0; a < layout.num_blocks; ++a) {
    auto s = std::make_unique<AgentState>(
        a, g.d, layout, g.measurements,
        gather_pose_columns(X, layout.poses[static_cast<std::size_t>(a)], g.d));
    s->Yn = gather_pose_columns(X, s->problem().neighbors(), g.d);
    s->Vn = s->Yn;
    if (space) s->use_coarse_space(space, g.measurements);
    out.push_back(std::move(s));
  }
  return out;
}

void expect_received_motions_are_the_all_to_all_ones(bool smoothed) {
  const Grid G = grid(600);
  const PoseGraph& g = G.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 7);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  CoarseOptions o;
  o.enabled = true;
  o.space = smoothed ? CoarseSpaceKind::kSmoothed : CoarseSpaceKind::kBlocks;
  o.aggregates = 3;
  std::shared_ptr<const CoarseSpace> space;
  if (smoothed)
    space = std::make_shared<const CoarseSpace>(
        make_coarse_space(g.num_poses, g.measurements, part, o));
  const int r = 4;
  const Eigen::MatrixXd X = bent(G.truth, r);
  auto full = agents(g, layout, space, X);
  auto sent = agents(g, layout, space, X);
  std::vector<std::vector<double>> terms;
  for (auto& s : full) terms.push_back(smoothed ? s->smoothed_coarse_terms() : s->coarse_terms());
  std::vector<const std::vector<double>*> pointers;
  for (const auto& t : terms) pointers.push_back(&t);
  const CoarseResult c = smoothed ? solve_smoothed_coarse(*space, r, pointers, o)
                                  : solve_coarse(layout, r, pointers, o);
  ASSERT_TRUE(c.moved);
  const int count = smoothed ? space->num_aggregates : layout.num_blocks;
  for (int a = 0; a < layout.num_blocks; ++a) {
    const std::vector<int> unknowns = coarse_unknowns_of(space.get(), layout, a);
    const ReceivedCoarseMotions got = read_coarse_motions(
        coarse_motions_message(0, 3, 7, unknowns, c.motions, c.cost_before - c.cost_after, true), r,
        count, unknowns);
    ASSERT_TRUE(got.applied);
    EXPECT_EQ(got.decrease, c.cost_before - c.cost_after);
    // Fewer motions than the whole coarse space, yet every pose this agent holds moves
    // exactly as it does under all motions.
    EXPECT_LT(unknowns.size(), static_cast<std::size_t>(count));
    AgentState& f = *full[static_cast<std::size_t>(a)];
    AgentState& s = *sent[static_cast<std::size_t>(a)];
    if (smoothed) {
      f.apply_smoothed_coarse(c.motions);
      s.apply_smoothed_coarse(got.motions);
    } else {
      f.apply_coarse(c.motions);
      s.apply_coarse(got.motions);
    }
    EXPECT_TRUE(f.Y == s.Y) << "agent " << a;
    EXPECT_TRUE(f.Yn == s.Yn) << "agent " << a;
    EXPECT_TRUE(f.Vn == s.Vn) << "agent " << a;
    EXPECT_FALSE(f.Y == gather_pose_columns(X, layout.poses[static_cast<std::size_t>(a)], g.d));
  }
}

TEST(CoarseExchange, EachAgentReceivesTheSmoothedMotionsTheAllToAllSolveComputed) {
  expect_received_motions_are_the_all_to_all_ones(true);
}

TEST(CoarseExchange, EachAgentReceivesTheBlockMotionsTheAllToAllSolveComputed) {
  expect_received_motions_are_the_all_to_all_ones(false);
}

TEST(CoarseExchange, MotionsForOtherUnknownsOrOfTheWrongSizeAreRejected) {
  Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(3, 4);
  Z.leftCols(3).setIdentity();
  const std::vector<Eigen::MatrixXd> motions(5, Z);
  const PoseBlockMessage m = coarse_motions_message(0, 1, 7, {1, 2}, motions, 0.5, true);
  EXPECT_NO_THROW(read_coarse_motions(m, 3, 5, {1, 2}));
  EXPECT_THROW(read_coarse_motions(m, 3, 5, {1, 3}), std::runtime_error);
  EXPECT_THROW(read_coarse_motions(m, 4, 5, {1, 2}), std::runtime_error);
  PoseBlockMessage short_one = m;
  short_one.data.pop_back();
  EXPECT_THROW(read_coarse_motions(short_one, 3, 5, {1, 2}), std::runtime_error);
  const ReceivedCoarseMotions none = read_coarse_motions(
      coarse_motions_message(0, 1, 7, {1, 2}, motions, 0.5, false), 3, 5, {1, 2});
  EXPECT_FALSE(none.applied);
  EXPECT_EQ(none.motions.size(), 5u);
}

// Whole runs: the gathered exchange gives the all-to-all iterates bit for bit (one solver
// instead of N on the same terms in the same order), also under shuffled delivery, with fewer
// bytes once there are a few agents.
void expect_gathered_rounds_equal_all_to_all(CoarseSpaceKind kind) {
  const Grid G = grid(800);
  const PoseGraph& g = G.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 9);
  DistributedOptions opt;
  opt.grad_norm_tol = 0.01;
  opt.coarse.enabled = true;
  opt.coarse.space = kind;
  opt.coarse.aggregates = 2;
  opt.coarse.gather = false;
  const DistributedResult all = solve_distributed(g, part, opt);
  opt.coarse.gather = true;
  const DistributedResult gathered = solve_distributed(g, part, opt);
  opt.delivery = DeliveryOrder::kShuffled;
  opt.delivery_seed = 11;
  const DistributedResult shuffled = solve_distributed(g, part, opt);
  EXPECT_EQ(gathered.stop_reason, "grad_norm");
  EXPECT_EQ(gathered.rounds, all.rounds);
  EXPECT_EQ(gathered.restarts, all.restarts);
  EXPECT_TRUE(gathered.X == all.X);
  EXPECT_TRUE(shuffled.X == all.X);
  EXPECT_LT(gathered.bytes_exchanged, all.bytes_exchanged);
}

TEST(CoarseExchange, GatheredSmoothedRoundsGiveTheAllToAllIteratesWithFewerBytes) {
  expect_gathered_rounds_equal_all_to_all(CoarseSpaceKind::kSmoothed);
}

TEST(CoarseExchange, GatheredBlockRoundsGiveTheAllToAllIteratesWithFewerBytes) {
  expect_gathered_rounds_equal_all_to_all(CoarseSpaceKind::kBlocks);
}

// A rollback (every agent resumes from its snapshot of round k, as after a lost agent rejoins)
// re-sends round k's terms and finishes exactly like the uninterrupted run.
TEST(CoarseExchange, GatheredRunResumedFromRoundSnapshotsIsBitIdentical) {
  const Grid G = grid(400);
  const PoseGraph& g = G.graph;
  DistributedOptions opt;
  opt.grad_norm_tol = 0.01;
  opt.coarse.enabled = true;
  opt.coarse.space = CoarseSpaceKind::kSmoothed;
  opt.coarse.aggregates = 2;
  const int N = 6, k = 5;
  auto smoothed = [&](test::AgentsOfRun& run) {
    std::vector<int> part(g.num_poses);
    for (std::size_t i = 0; i < g.num_poses; ++i) part[i] = run.layout.owner[i];
    const auto space = std::make_shared<const CoarseSpace>(
        make_coarse_space(g.num_poses, g.measurements, part, opt.coarse));
    for (auto& s : run.states) s->use_coarse_space(space, g.measurements);
  };
  test::AgentsOfRun first(g, N, opt);
  smoothed(first);
  std::map<int, ProtocolSnapshot> at_k;
  for (int b = 0; b < N; ++b)
    first.agents[static_cast<std::size_t>(b)]->set_round_observer(
        [&at_k, b](const ProtocolSnapshot& s) {
          if (s.round == k) at_k[b] = s;
        });
  run_in_process(first.agents, DeliveryOrder::kFifo);
  ASSERT_EQ(at_k.size(), static_cast<std::size_t>(N));
  ASSERT_GT(first.agents[0]->rounds(), k + 5);
  ASSERT_GT(first.agents[0]->coarse_corrections(), k);
  std::vector<ProtocolSnapshot> snapshots;
  for (int b = 0; b < N; ++b) snapshots.push_back(at_k[b]);
  test::AgentsOfRun second(g, N, opt);
  smoothed(second);
  resume_in_process(second.agents, snapshots, DeliveryOrder::kShuffled, 3);
  for (std::size_t b = 0; b < static_cast<std::size_t>(N); ++b) {
    EXPECT_TRUE(first.states[b]->Y == second.states[b]->Y) << "agent " << b;
    EXPECT_EQ(first.agents[b]->rounds(), second.agents[b]->rounds());
    EXPECT_EQ(first.agents[b]->trace().back().cost, second.agents[b]->trace().back().cost);
  }
}

}  // namespace
}  // namespace tessera
