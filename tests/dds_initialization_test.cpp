// The agents' initialisation stage (core/runtime/initialization_stage.hpp), over DDS and in
// process.
//  - In process (threads and an in-memory channel, no DDS): every agent's poses equal core's
//    chordal / distributed initialisation of the whole graph bit for bit.
//  - Over DDS (processes): a graph without VERTEX lines, `--init distributed` and the default
//    (chordal), gives the in-process engine's rounds and cost; the coordinator's `highest`
//    partition is the one `tessera solve` computes from the file.
// Domains used here: 201-203 and 177 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/util/input_error.hpp>
#include <thread>

#include "dds_process_support.hpp"
#include "initialization_threads.hpp"
#include "runtime/initialization_stage.hpp"
#include "runtime/known_inlier_start.hpp"
#include "thread_exchange.hpp"

namespace tessera::test::dds {
namespace {

// ---------------------------------------------------------------- in process

// Like ThreadChannel, but what this agent sends to agent `slow` arrives `delay` later (DDS
// orders one sender's messages, not messages of different senders to one recipient).
class LaggingChannel : public agent::ProtocolChannel {
 public:
  LaggingChannel(ThreadExchange& ex, std::uint32_t self, std::uint32_t slow,
                 std::chrono::milliseconds delay)
      : ex_(ex), self_(self), slow_(slow), delay_(delay) {}
  ~LaggingChannel() override {
    for (auto& t : late_) t.join();
  }
  void send(const OutgoingMessage& m) override {
    OutgoingMessage now = m, later = m;
    now.broadcast = later.broadcast = false;
    now.recipients.clear();
    later.recipients.clear();
    for (std::uint32_t a = 0; a < ex_.size(); ++a)
      if (a != self_ && (m.broadcast || std::find(m.recipients.begin(), m.recipients.end(), a) !=
                                            m.recipients.end()))
        (a == slow_ ? later : now).recipients.push_back(a);
    if (!now.recipients.empty()) ex_.post(self_, now);
    if (!later.recipients.empty())
      late_.emplace_back([this, later] {
        std::this_thread::sleep_for(delay_);
        ex_.post(self_, later);
      });
  }
  std::optional<ProtocolMessage> receive(double timeout_s) override {
    return ex_.take(self_, timeout_s);
  }

 private:
  ThreadExchange& ex_;
  std::uint32_t self_, slow_;
  std::chrono::milliseconds delay_;
  std::vector<std::thread> late_;
};

// Runs the stage for every agent in its own thread; returns the poses in global order.
std::vector<Pose> run_stage(const PoseGraph& g, std::uint32_t N, const std::string& method,
                            std::size_t* leftover = nullptr) {
  const StageThreadsRun run = run_initialization_threads(g, N, method);
  for (std::uint32_t k = 0; k < N; ++k)
    EXPECT_EQ(run.results[k].poses.size(), run.shares[k].end - run.shares[k].begin);
  if (leftover) *leftover = run.left_over;
  return run.poses();
}

PoseGraph generated(TrajectoryKind kind, std::size_t poses, std::size_t robots,
                    std::uint64_t seed) {
  GeneratorOptions o;
  o.kind = kind;
  o.num_poses = poses;
  o.num_robots = robots;
  o.seed = seed;
  return generate_pose_graph(o).graph;
}

TEST(DdsInitializationStage, DistributedGivesCoresPosesBitForBit) {
  // 250 poses among 4 robots: uneven ranges; 2D and 3D.
  for (auto kind : {TrajectoryKind::kCity, TrajectoryKind::kGrid3d}) {
    const PoseGraph g = generated(kind, 250, 4, 11);
    std::size_t leftover = 1;
    const std::vector<Pose> dds = run_stage(g, 4, "distributed", &leftover);
    expect_identical(dds, initial_poses(g, DistributedInit::kDistributed, 4));
    EXPECT_EQ(leftover, 0u) << "every message of the stage is consumed inside it";
  }
}

TEST(DdsInitializationStage, ChordalGivesCoresPosesBitForBit) {
  const PoseGraph g = generated(TrajectoryKind::kGrid3d, 200, 3, 4);
  std::size_t leftover = 1;
  expect_identical(run_stage(g, 3, "chordal", &leftover),
                   initial_poses(g, DistributedInit::kChordal, 3));
  EXPECT_EQ(leftover, 0u);
  // The default is the in-process engine's default.
  EXPECT_EQ(agent::default_initialization(), init_name(DistributedOptions{}.initialization));
  expect_identical(run_stage(g, 3, ""), initial_poses(g, DistributedOptions{}.initialization, 3));
}

// A robust run's two starts back to back on one inbox (the run's initialization, then the
// distributed one of the known inliers, the same method so the phases would collide without
// the offset): agent 2's messages reach agent 0 late, so agent 1's second-stage messages reach
// agent 0 while it still waits in the first; both results are the in-process engine's, bit
// for bit, nothing left over (two separate stages would drop those messages and time out).
TEST(DdsInitializationStage, TwoStagesOnOneInboxKeepALateAgentsMessages) {
  const PoseGraph g = generated(TrajectoryKind::kGrid3d, 216, 3, 4);
  const std::uint32_t N = 3;
  ThreadExchange ex(N);
  const auto structure = structure_of(g);
  std::vector<agent::RobotShare> shares;
  std::vector<agent::KnownInlierStart> known;
  for (std::uint32_t k = 0; k < N; ++k) {
    shares.push_back(agent::robot_share(g, k, N));
    auto s = agent::known_inlier_start(shares[k], structure, KnownInliers::kOdometry);
    ASSERT_TRUE(s.has_value());
    known.push_back(std::move(*s));
  }
  std::vector<std::vector<Pose>> first(N), second(N);
  std::vector<std::string> errors(N);
  std::vector<std::thread> threads;
  for (std::uint32_t k = 0; k < N; ++k)
    threads.emplace_back([&, k] {
      LaggingChannel ch(ex, k, k == 2 ? 0 : N, std::chrono::milliseconds(300));
      try {
        auto [a, b] = agent::run_initialization_stages(shares[k], known[k].share, k, N, structure,
                                                       known[k].structure, "distributed",
                                                       "distributed", "test", ch, 5.0);
        first[k] = std::move(a.poses);
        second[k] = std::move(b.poses);
      } catch (const std::exception& e) {
        errors[k] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  std::vector<Pose> all_first, all_second;
  for (std::uint32_t k = 0; k < N; ++k) {
    EXPECT_EQ(errors[k], "") << "agent " << k;
    all_first.insert(all_first.end(), first[k].begin(), first[k].end());
    all_second.insert(all_second.end(), second[k].begin(), second[k].end());
  }
  EXPECT_EQ(ex.left_over(), 0u);
  expect_identical(all_first, initial_poses(g, DistributedInit::kDistributed, 3));
  PoseGraph odometry = g;
  odometry.measurements.clear();
  for (const auto& m : g.measurements)
    if (is_known_inlier(m, KnownInliers::kOdometry)) odometry.measurements.push_back(m);
  expect_identical(all_second, initial_poses(odometry, DistributedInit::kDistributed, 3));
}

TEST(DdsInitializationStage, OneAgentNeedsNoMessages) {
  const PoseGraph g = generated(TrajectoryKind::kCity, 80, 1, 2);
  expect_identical(run_stage(g, 1, "distributed"),
                   initial_poses(g, DistributedInit::kDistributed, 1));
  expect_identical(run_stage(g, 1, "chordal"), initial_poses(g, DistributedInit::kChordal, 1));
}

TEST(DdsInitializationStage, FileWithoutVertexLinesAndUnknownNamesAreInputErrors) {
  PoseGraph g = generated(TrajectoryKind::kCity, 60, 2, 3);
  g.initial.clear();
  const agent::RobotShare share = agent::robot_share(g, 1, 2);
  ThreadExchange ex(2);
  ThreadChannel ch(ex, 1);
  try {
    agent::run_initialization_stage(share, 1, 2, structure_of(g), "file", "robot1.g2o", ch, 1.0);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("robot1.g2o"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("VERTEX"), std::string::npos) << e.what();
  }
  EXPECT_THROW(
      agent::run_initialization_stage(share, 1, 2, structure_of(g), "odometry", "x", ch, 1.0),
      InputError);
}

TEST(DdsInitializationStage, AMissingPeerTimesOutNamingIt) {
  const PoseGraph g = generated(TrajectoryKind::kCity, 60, 3, 3);
  const agent::RobotShare share = agent::robot_share(g, 0, 3);
  ThreadExchange ex(3);
  ThreadChannel ch(ex, 0);
  try {
    agent::run_initialization_stage(share, 0, 3, structure_of(g), "distributed", "x", ch, 0.2);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("waiting for agent(s) 1 2"), std::string::npos)
        << e.what();
  }
}

TEST(DdsInitializationStage, PhasesCannotCollideWithTheRoundLoops) {
  EXPECT_GT(agent::kInitPhaseBase, agent::kRoundingPhaseBase + 50);
  EXPECT_GT(agent::kInitPhaseBase, static_cast<std::uint32_t>(ProtocolPhase::kRedoStatus));
}

// ---------------------------------------------------------------- over DDS

// Coordinator + agents (started in reverse id order) on `graph`; returns the summary JSON.
std::string run_dds(const std::string& dir, const std::string& graph, int agents, int domain,
                    const std::vector<std::string>& solver_args) {
  const std::string run = "init-" + std::to_string(getpid()) + "-" + std::to_string(domain);
  std::vector<std::string> cargs = {"--timeout", "20",        "--run-timeout",
                                    "60",        "--summary", dir + "/summary.json"};
  cargs.insert(cargs.end(), solver_args.begin(), solver_args.end());
  run_to_the_end(dir, graph, agents, run, domain, cargs, 90, true);
  return slurp(dir + "/summary.json");
}

// A generated graph with its VERTEX lines removed (like CSAIL: edges only).
std::string graph_without_vertices(const std::string& dir, const std::string& kind, int poses,
                                   int robots) {
  const std::string full = dir + "/full.g2o", path = dir + "/edges_only.g2o";
  generate_graph(full, "--kind " + kind + " --poses " + std::to_string(poses) + " --robots " +
                           std::to_string(robots) + " --seed 9");
  std::ifstream in(full);
  std::ofstream o(path);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VERTEX", 0) != 0) o << line << "\n";
  return path;
}

void expect_same_as_solve(const std::string& init, int domain,
                          const std::vector<std::string>& extra = {}) {
  const std::string dir = temp_dir();
  const int N = 3;
  const std::string graph = graph_without_vertices(dir, "grid3d", 250, N);
  std::vector<std::string> args = {"--partition", "highest",          "--seed",
                                   "3",           "--partition-seed", "3"};
  if (!init.empty()) args.insert(args.end(), {"--init", init});
  args.insert(args.end(), extra.begin(), extra.end());
  const std::string summary = run_dds(dir, graph, N, domain, args);
  const PoseGraph g = read_g2o(graph);
  ASSERT_FALSE(g.has_initial());

  // What `tessera solve --agents 3 --partition highest --seed 3 [--init X]` does.
  PartitionOptions popt;
  popt.parts = N;
  popt.preset = parse_preset("highest");
  popt.seed = 3;
  popt.objective = PartitionObjective::kRounds;  // solve's and the coordinator's default
  const std::vector<int> part =
      partition_graph(graph_structure_from_pose_graph(g), popt).assignment;
  EXPECT_EQ(assignment_of(dir, N), part) << "the coordinator's partition is not solve's";
  DistributedOptions opt;
  opt.seed = 3;
  if (!init.empty()) opt.initialization = parse_init(init);
  const DistributedResult ref = solve_distributed(g, part, opt);
  ASSERT_GT(ref.rounds, 1);
  EXPECT_EQ(json_field(summary, "rounds"), ref.rounds) << summary;
  EXPECT_EQ(json_field(summary, "restarts"), ref.restarts) << summary;
  EXPECT_NEAR(json_field(summary, "cost"), ref.cost, 1e-9 * ref.cost) << summary;
  EXPECT_NEAR(json_field(summary, "grad_norm"), ref.grad_norm, 1e-9 * ref.grad_norm) << summary;
  const std::string expect_init =
      init.empty() ? init_name(DistributedOptions{}.initialization) : init;
  EXPECT_NE(summary.find("\"init\": \"" + expect_init + "\""), std::string::npos) << summary;
}

TEST(DdsInitialization, DistributedOverDdsGivesTheInProcessIterates) {
  expect_same_as_solve("distributed", 201);
}

TEST(DdsInitialization, DefaultOverDdsIsSolvesDefaultWithTheSameIterates) {
  expect_same_as_solve("", 202);
}

// The local solves one agent at a time (core/runtime/setup_turns.hpp), through the coordinator's
// assignment: the same initial poses, so the same iterates.
TEST(DdsInitialization, DistributedInTurnsOfOneGivesTheInProcessIterates) {
  expect_same_as_solve("distributed", 177, {"--setup-at-once", "1"});
}

}  // namespace
}  // namespace tessera::test::dds
