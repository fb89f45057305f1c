// `tessera replay` over DDS: a reader of the online input topic absorbs the batches into the
// stream model and ends with the batch graph (same poses, same measurements), whether it
// subscribed before the replay started or after it finished playing.
// Domains used here: 139-140 (each test its own).

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tuple>

#include "dds_process_support.hpp"
#include "transport/graph_stream_topic.hpp"

namespace tessera::test::dds {
namespace {

// Reads until every robot sent its last batch (or `timeout_s`).
GraphStream read_stream(transport::GraphStreamReader& reader, int d, std::size_t robots,
                        double timeout_s) {
  GraphStream stream(d, "tessera_graph_stream");
  std::set<std::uint32_t> finished;
  const auto start = Clock::now();
  while (finished.size() < robots &&
         std::chrono::duration<double>(Clock::now() - start).count() < timeout_s)
    for (const auto& r : reader.take(0.1)) {
      EXPECT_EQ(r.dim, d);
      stream.absorb(r.batch);
      if (r.last) finished.insert(r.batch.robot);
    }
  EXPECT_EQ(finished.size(), robots);
  return stream;
}

// The stream's graph equals the file's: poses in robot order are the file's contiguous ranges.
void expect_same_graph(const GraphStream& stream, const PoseGraph& whole, std::size_t robots) {
  const PoseGraph& got = stream.graph();
  ASSERT_EQ(got.num_poses, whole.num_poses);
  ASSERT_EQ(got.measurements.size(), whole.measurements.size());
  std::vector<std::size_t> begin(robots + 1, 0);
  for (std::size_t r = 0; r <= robots; ++r) begin[r] = r * whole.num_poses / robots;
  auto original = [&](std::size_t id) {
    const PoseKey k = stream.key_of_pose()[id];
    return begin[k.robot] + k.index;
  };
  using Edge = std::tuple<std::size_t, std::size_t, double, double, double, double>;
  std::multiset<Edge> want, have;
  for (const auto& m : whole.measurements)
    want.insert({m.i, m.j, m.t(0), m.t(1), m.R(0, 1), m.tau});
  for (const auto& m : got.measurements)
    have.insert({original(m.i), original(m.j), m.t(0), m.t(1), m.R(0, 1), m.tau});
  EXPECT_TRUE(want == have);
  EXPECT_EQ(stream.held_measurements(), 0u);
}

TEST(DdsReplay, AReaderStartedFirstReceivesTheBatchGraph) {
  const std::string dir = temp_dir();
  generate_graph(dir + "/city.g2o", "--kind city --poses 150 --robots 3");
  transport::GraphStreamReader reader(139, "replay-first");
  Process replay = start(
      {bin("tessera"), "replay", dir + "/city.g2o", "--robots", "3", "--run-id", "replay-first",
       "--domain", "139", "--rate", "400", "--wait-readers", "1", "--linger", "1"},
      dir + "/replay.log");
  const GraphStream stream = read_stream(reader, 2, 3, 60);
  ASSERT_TRUE(wait_all({&replay}, 60));
  EXPECT_EQ(replay.exit_code, 0) << replay.output();
  expect_same_graph(stream, read_g2o(dir + "/city.g2o"), 3);
}

TEST(DdsReplay, AReaderStartedAfterThePlayStillReceivesEverything) {
  const std::string dir = temp_dir();
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " generate --kind grid3d --poses 120 --robots 2 --out " +
                            dir + "/grid.g2o --split " + dir + "/robots",
                        &out),
            0)
      << out;
  Process replay =
      start({bin("tessera"), "replay", dir + "/robots", "--run-id", "replay-late", "--domain",
             "140", "--rate", "1000", "--linger", "20", "--json", dir + "/replay.json"},
            dir + "/replay.log");
  ASSERT_TRUE(wait_for_output(replay, "replayed", 60)) << replay.output();
  transport::GraphStreamReader reader(140, "replay-late");
  const GraphStream stream = read_stream(reader, 3, 2, 30);
  kill(replay.pid, SIGTERM);
  wait_all({&replay}, 20);
  expect_same_graph(stream, read_g2o(dir + "/grid.g2o"), 2);
}

TEST(DdsReplay, BadArgumentsExitWithCode2NamingTheProblem) {
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " replay /nonexistent.g2o --run-id x", &out), 2);
  EXPECT_NE(out.find("/nonexistent.g2o"), std::string::npos) << out;
  EXPECT_EQ(run_command(bin("tessera") + " replay g.g2o", &out), 2);
  EXPECT_NE(out.find("--run-id"), std::string::npos) << out;
  EXPECT_EQ(run_command(bin("tessera") + " replay g.g2o --run-id x --rate 0", &out), 2);
  EXPECT_NE(out.find("rate"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::test::dds
