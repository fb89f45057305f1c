// The coordinator's early partition of the graph file (coordinator/file_partition.hpp: what
// `tessera launch` uses to partition while the agents start up): it is the partition of the
// structure the agents announce, it is used only when that structure is the file's, and a
// coordinator given another file (or none it can read) partitions the announcements instead.
// Domains used here: 54, 55 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <thread>
#include <vector>

#include "announcement_support.hpp"
#include "coordinator/file_partition.hpp"
#include "coordinator/partition_priority.hpp"
#include "coordinator/run_structure.hpp"
#include "dds_process_support.hpp"
#include "runtime/local_share.hpp"

namespace tessera::test::dds {
namespace {

TEST(DdsFilePartition, IsThePartitionOfTheAnnouncedStructure) {
  const std::string dir = temp_dir();
  // Robots' measurements interleave in a generated file, so file order != agent order.
  // `highest`, the benchmarks' preset, on a small graph (its evolutionary search is slow).
  const std::string path =
      generate_graph(dir + "/g.g2o", "--kind grid3d --poses 120 --robots 4 --seed 6");
  const PoseGraph g = read_g2o(path);
  const coordinator::RunStructure rs =
      coordinator::merge_announcements(announcements_of(g, 4), 4, "r");
  const coordinator::PartitionStepResult announced =
      coordinator::partition_for_agents(rs.graph, 4, "highest", 3);
  EXPECT_FALSE(announced.early);

  std::string why;
  const auto fp = coordinator::partition_graph_file(path, 4, "highest", 3, &why);
  ASSERT_TRUE(fp) << why;
  EXPECT_TRUE(fp->fits(rs));
  EXPECT_TRUE(fp->part.early);
  EXPECT_EQ(fp->part.owner, announced.owner);
  EXPECT_EQ(fp->part.cut_edges, announced.cut_edges);

  // The same on its own thread, which reports when it ran.
  coordinator::FilePartitionJob job(path, 4, "highest", 3);
  std::chrono::steady_clock::time_point started, ended;
  const auto threaded = job.take(&why, &started, &ended);
  ASSERT_TRUE(threaded) << why;
  EXPECT_EQ(threaded->part.owner, announced.owner);
  EXPECT_LE(started, ended);
}

// The partition thread's priority (coordinator/partition_priority.hpp) is asked for, not
// assumed: the thread reports how far its nice went down (as asked where the process may lower
// it, e.g. as root; 0 otherwise), and the partition does not depend on it. No DDS.
TEST(DdsFilePartition, ItsThreadReportsTheNiceItGotAndPartitionsTheSame) {
  int before = 0, got = 0, after = 0;
  std::thread([&] {
    const auto tid = static_cast<id_t>(syscall(SYS_gettid));
    before = getpriority(PRIO_PROCESS, tid);
    got = coordinator::lower_partition_thread_nice(-3);
    after = getpriority(PRIO_PROCESS, tid);
  }).join();
  EXPECT_EQ(after - before, got);
  EXPECT_TRUE(got == -3 || got == 0 || after == -20) << got;
  // This thread's nice is its own.
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))), before);

  const std::string dir = temp_dir();
  const std::string path =
      generate_graph(dir + "/g.g2o", "--kind grid3d --poses 200 --robots 4 --seed 6");
  std::string why;
  coordinator::FilePartitionJob plain(path, 4, "fast", 2);
  coordinator::FilePartitionJob raised(path, 4, "fast", 2, 0.0, -3);
  const auto a = plain.take(&why, nullptr, nullptr);
  const auto b = raised.take(&why, nullptr, nullptr);
  ASSERT_TRUE(a && b) << why;
  EXPECT_EQ(a->part.thread_nice, 0);
  EXPECT_EQ(b->part.thread_nice, got);
  EXPECT_EQ(a->part.owner, b->part.owner);
}

TEST(DdsFilePartition, AnotherStructureDoesNotFitAndAnUnreadableFileIsNoPartition) {
  const std::string dir = temp_dir();
  const std::string path =
      generate_graph(dir + "/g.g2o", "--kind grid3d --poses 300 --robots 4 --seed 6");
  // Same poses, other loop closures.
  const std::string other =
      generate_graph(dir + "/other.g2o", "--kind grid3d --poses 300 --robots 4 --seed 7");
  const coordinator::RunStructure rs =
      coordinator::merge_announcements(announcements_of(read_g2o(path), 4), 4, "r");
  std::string why;
  const auto fp = coordinator::partition_graph_file(other, 4, "eco", 1, &why);
  ASSERT_TRUE(fp) << why;
  EXPECT_FALSE(fp->fits(rs));
  // One measurement's endpoints changed is enough.
  auto same = coordinator::partition_graph_file(path, 4, "eco", 1, &why);
  ASSERT_TRUE(same) << why;
  EXPECT_TRUE(same->fits(rs));
  std::swap(same->edge_i[5], same->edge_j[5]);
  EXPECT_FALSE(same->fits(rs));

  EXPECT_FALSE(coordinator::partition_graph_file(dir + "/missing.g2o", 4, "eco", 1, &why));
  EXPECT_NE(why.find("missing.g2o"), std::string::npos) << why;
  coordinator::FilePartitionJob job(dir + "/missing.g2o", 4, "eco", 1);
  EXPECT_FALSE(job.take(nullptr, nullptr, nullptr));
}

// Coordinator `--graph coordinator_file` + 3 agents on `graph` (coordinator first, so the
// agents start while it partitions); the agents' owners must be `partition_graph` of `graph`.
// Preset `eco` (7 ms of CPU for this graph), not `highest` (2.1 CPU-s): with another file the
// coordinator partitions twice while the agents wait for their assignment under their 20 s
// --timeout, and at load 12-21 on a 2-core host the two `highest` partitions took 25-34 s of
// wall. Which partition the run uses does not depend on the preset.
void expect_partition_of_the_agents_graph(const std::string& coordinator_file, int domain,
                                          bool expect_early) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 250 --robots 3 --seed 4");
  generate_graph(dir + "/other.g2o", "--kind grid3d --poses 250 --robots 3 --seed 8");
  const std::string run = "filepart-" + std::to_string(getpid()) + "-" + std::to_string(domain);
  const std::vector<std::string> cargs = {"--timeout",        "20",
                                          "--run-timeout",    "60",
                                          "--summary",        dir + "/summary.json",
                                          "--init",           "file",
                                          "--partition",      "eco",
                                          "--partition-seed", "2",
                                          "--graph",          dir + "/" + coordinator_file,
                                          "--verbose"};
  run_to_the_end(dir, graph, 3, run, domain, cargs, 90);
  PartitionOptions popt;
  popt.parts = 3;
  popt.preset = parse_preset("eco");
  popt.seed = 2;
  popt.objective = PartitionObjective::kRounds;  // the coordinator's (partition_step.hpp)
  const std::vector<int> part =
      partition_graph(graph_structure_from_pose_graph(read_g2o(graph)), popt).assignment;
  EXPECT_EQ(assignment_of(dir, 3), part) << "not the partition of the agents' graph";
  const std::string summary = slurp(dir + "/summary.json");
  EXPECT_NE(summary.find(std::string("\"partition_early\": ") + (expect_early ? "true" : "false")),
            std::string::npos)
      << summary;
  // The partition's CPU is its thread's (at most its wall, here measured around the same call);
  // the run waits for it after the announcements at most its whole wall when it partitions
  // the announced structure, and that wait is part of the critical path either way.
  const double part_ms = json_number(summary, "partition_ms");
  const double cpu_ms = json_number(summary, "partition_cpu_ms");
  const double wait_ms = json_number(summary, "partition_wait_ms");
  EXPECT_GT(cpu_ms, 0.0) << summary;
  EXPECT_LE(cpu_ms, part_ms + 5.0) << summary;
  EXPECT_GE(wait_ms, 0.0) << summary;
  if (!expect_early) {
    EXPECT_GE(wait_ms, part_ms) << summary;
  }
  const std::string log = slurp(dir + "/coordinator.log");
  EXPECT_EQ(log.find("partitioning the announced") != std::string::npos, !expect_early) << log;
}

TEST(DdsFilePartition, CoordinatorWithTheAgentsFileUsesItsEarlyPartition) {
  expect_partition_of_the_agents_graph("graph.g2o", 54, true);
}

TEST(DdsFilePartition, CoordinatorWithAnotherFilePartitionsTheAnnouncements) {
  expect_partition_of_the_agents_graph("other.g2o", 55, false);
}

}  // namespace
}  // namespace tessera::test::dds
