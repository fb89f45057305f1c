// An online agent's batch latencies (agent/online_batch_arrivals.hpp): from a batch's arrival to
// the end of the solve that absorbed it, and the same with the solve's CPU time in place of its
// wall time.

#include "agent/online_batch_arrivals.hpp"

#include <gtest/gtest.h>

#include <tessera/online/graph_stream.hpp>
#include <vector>

namespace tessera::agent {
namespace {

StreamBatch one_pose_batch(std::uint64_t sequence) {
  StreamBatch b;
  b.robot = 0;
  b.sequence = sequence;
  b.stamp = static_cast<double>(sequence);
  StreamPose p;
  p.key = {0, sequence};
  p.guess = Pose::identity(3);
  b.poses.push_back(p);
  return b;
}

TEST(BatchArrivals, AbsorbedBatchesGetTheirWallAndCpuLatencyAndAreForgotten) {
  GraphStream stream(3);
  BatchArrivals arrivals;
  arrivals.arrived(0, 0, 1.0);
  arrivals.arrived(0, 1, 1.5);
  arrivals.arrived(0, 2, 1.8);  // not absorbed by this solve
  stream.absorb(one_pose_batch(0));
  stream.absorb(one_pose_batch(1));
  std::vector<double> wall, cpu;
  // The solve started at 2.0, ended at 3.0 and took 0.25 s of CPU.
  const double oldest = arrivals.absorbed(stream, 3.0, 2.0, wall, 0.25, &cpu);
  EXPECT_DOUBLE_EQ(oldest, 1.0);
  ASSERT_EQ(wall.size(), 2u);
  ASSERT_EQ(cpu.size(), 2u);
  EXPECT_DOUBLE_EQ(wall[0], 2.0);
  EXPECT_DOUBLE_EQ(wall[1], 1.5);
  EXPECT_DOUBLE_EQ(cpu[0], 1.25);  // waited 1.0 until the solve, then its 0.25 CPU-s
  EXPECT_DOUBLE_EQ(cpu[1], 0.75);
  // Absorbed batches are forgotten: a later solve counts only batch 2.
  stream.absorb(one_pose_batch(2));
  wall.clear();
  cpu.clear();
  arrivals.absorbed(stream, 5.0, 4.0, wall, 0.5, &cpu);
  ASSERT_EQ(wall.size(), 1u);
  EXPECT_DOUBLE_EQ(wall[0], 3.2);
  EXPECT_DOUBLE_EQ(cpu[0], 2.7);
}

}  // namespace
}  // namespace tessera::agent
