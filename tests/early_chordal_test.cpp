// Agent 0's chordal initialization started before the initialisation stage
// (core/runtime/early_chordal.hpp): the stage uses it only for exactly the graph it solved,
// and every agent's poses are then the ones the stage computes without it, bit for bit.
// In process (threads and an in-memory channel), no DDS.

#include "runtime/early_chordal.hpp"

#include <gtest/gtest.h>

#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <vector>

#include "initialization_threads.hpp"

namespace tessera::test {
namespace {

PoseGraph grid(std::size_t poses, std::size_t robots) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = poses;
  o.num_robots = robots;
  o.seed = 3;
  return generate_pose_graph(o).graph;
}

struct StageRun {
  std::vector<Pose> poses;  // every agent's, in global order
  std::vector<bool> early;  // InitializationResult::early of each agent
};

// The chordal stage of N agents holding robot_share(g, k, N), agent 0 given `early` (or none).
StageRun chordal_stage(const PoseGraph& g, std::uint32_t N, agent::EarlyChordal* early) {
  const StageThreadsRun stage = run_initialization_threads(g, N, "chordal", early);
  StageRun run;
  run.poses = stage.poses();
  for (const auto& r : stage.results) run.early.push_back(r.early);
  EXPECT_EQ(stage.left_over, 0u);
  return run;
}

TEST(EarlyChordal, GivesTheChordalInitializationOfItsGraphOnce) {
  const PoseGraph g = grid(300, 3);
  agent::EarlyChordal early(g);
  const auto poses = early.take_if_same(g);
  ASSERT_TRUE(poses.has_value());
  expect_identical(*poses, chordal_initialization(g));
  EXPECT_FALSE(early.take_if_same(g).has_value());
}

TEST(EarlyChordal, RefusesAGraphThatDiffersInOneValue) {
  const PoseGraph g = grid(200, 2);
  PoseGraph other = g;
  other.measurements[57].t(1) += 1e-12;
  {
    agent::EarlyChordal early(g);
    EXPECT_FALSE(early.take_if_same(other).has_value());
  }
  other = g;
  other.measurements[3].kappa *= 2;
  EXPECT_FALSE(agent::same_chordal_problem(g, other));
  other = g;
  other.measurements.pop_back();
  EXPECT_FALSE(agent::same_chordal_problem(g, other));
  other = g;
  other.initial.clear();  // the chordal solve does not read the initial poses
  other.source = "elsewhere";
  EXPECT_TRUE(agent::same_chordal_problem(g, other));
}

TEST(EarlyChordal, TheStageUsesItAndGivesTheSamePosesAsWithout) {
  const PoseGraph g = grid(400, 4);
  const StageRun without = chordal_stage(g, 4, nullptr);
  agent::EarlyChordal early(g);
  const StageRun with = chordal_stage(g, 4, &early);
  expect_identical(with.poses, without.poses);
  EXPECT_TRUE(with.early[0]);
  for (std::uint32_t k = 1; k < 4; ++k) EXPECT_FALSE(with.early[k]) << "agent " << k;
  EXPECT_FALSE(without.early[0]);
}

TEST(EarlyChordal, TheStageSolvesTheGatheredGraphWhenTheEarlyOneIsAnother) {
  const PoseGraph g = grid(400, 4);
  PoseGraph stale = g;  // e.g. the file changed after the fork server parsed it
  stale.measurements[120].R = stale.measurements[121].R;
  const StageRun without = chordal_stage(g, 4, nullptr);
  agent::EarlyChordal early(stale);
  const StageRun with = chordal_stage(g, 4, &early);
  EXPECT_FALSE(with.early[0]);
  expect_identical(with.poses, without.poses);
}

}  // namespace
}  // namespace tessera::test
