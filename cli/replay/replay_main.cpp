// `tessera replay` (run by `tessera`, which never links Fast DDS): plays a multi-robot graph
// onto the online input topic as the robots' front ends would (docs/online.md).

#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/util/input_error.hpp>
#include <thread>
#include <vector>

#include "arguments.hpp"
#include "json_writer.hpp"
#include "robot_files.hpp"
#include "runtime/replay_input.hpp"
#include "transport/graph_stream_topic.hpp"
#include "transport/run_identity.hpp"

namespace {

const char* const kHelp =
    "usage: tessera replay GRAPH --run-id ID [options]\n"
    "\n"
    "Plays a multi-robot pose graph onto the DDS topic tessera_graph_stream (partition = run\n"
    "id) as the robots' SLAM front ends would (docs/online.md): each robot moves along its own\n"
    "poses at --rate poses per second and publishes each new pose with its odometry; a loop\n"
    "closure is published once both of its poses exist, by the robot that reached its pose\n"
    "last. The topic keeps every batch for readers that start later (agents started after\n"
    "the replay), as long as the replay runs.\n"
    "\n"
    "  GRAPH                    a g2o file (robots: --robots), the per-robot files of\n"
    "                           `generate --split` as a folder or a comma-separated list\n"
    "  --run-id ID              the run to feed, 1..64 of [A-Za-z0-9_.-] (required)\n"
    "  --domain D               DDS domain 0..232        [derived from the run id]\n"
    "  --robots R               robots sharing a whole g2o file, contiguous id ranges [1]\n"
    "  --rate R                 poses per second per robot, > 0                [10]\n"
    "  --speedup S              play S times faster than real time, > 0       [1]\n"
    "  --start S0,S1,...        seconds (before the speedup) at which each robot starts\n"
    "                           moving; missing robots start at 0            [all 0]\n"
    "  --wait-readers K         wait until K readers are matched before playing [0]\n"
    "  --wait-s T               at most T seconds for them (then exit 2)       [30]\n"
    "  --linger S               stay S seconds after the last batch for late readers [0]\n"
    "  --json FILE              write a JSON summary\n"
    "  --help                   this text\n";

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run(const std::vector<std::string>& argv) {
  using namespace tessera;
  const cli::Arguments args(argv,
                            {"run-id", "domain", "robots", "rate", "speedup", "start",
                             "wait-readers", "wait-s", "linger", "json"},
                            {"help"});
  if (args.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (args.positional().size() != 1) throw InputError("expected one GRAPH argument (see --help)");
  const auto run_id = args.get("run-id");
  if (!run_id) throw InputError("option --run-id ID is required (see --help)");
  transport::validate_run_id(*run_id);
  const long domain = args.get_long("domain", transport::domain_for_run(*run_id));
  if (domain < 0 || domain > transport::kMaxDomain)
    throw InputError("option --domain: must be 0.." + std::to_string(transport::kMaxDomain));
  ReplayOptions options;
  options.rate = args.get_double("rate", options.rate);
  options.speedup = args.get_double("speedup", options.speedup);
  for (const std::string& s : args.get_list("start")) {
    try {
      options.start_s.push_back(std::stod(s));
    } catch (const std::exception&) {
      throw InputError("option --start: '" + s + "' is not a number");
    }
  }
  options.validate();
  const long wait_readers = args.get_long("wait-readers", 0);
  const double wait_s = args.get_double("wait-s", 30.0);
  const double linger_s = args.get_double("linger", 0.0);
  if (wait_readers < 0) throw InputError("option --wait-readers: must be >= 0");
  if (!(wait_s >= 0)) throw InputError("option --wait-s: must be >= 0");
  if (!(linger_s >= 0)) throw InputError("option --linger: must be >= 0");

  const std::string graph = args.positional().front();
  const auto files = cli::robot_files_of(graph);
  const long robots = args.get_long("robots", 1);
  if (!files.empty() && args.has("robots"))
    throw InputError("option --robots: robot files say who owns what; use it with one g2o file");
  const runtime::ReplayInput input =
      files.empty() ? runtime::replay_input_from_file(
                          graph, robots > 0 ? static_cast<std::size_t>(robots) : 0)
                    : runtime::replay_input_from_robot_files(files);
  if (options.start_s.size() > input.robots)
    throw InputError("option --start: " + std::to_string(options.start_s.size()) +
                     " start times for " + std::to_string(input.robots) + " robots");
  const ReplayPlan plan = plan_replay(input.graph, input.robot_of_pose, options);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  transport::GraphStreamWriter writer(static_cast<int>(domain), *run_id);
  const auto wait_start = std::chrono::steady_clock::now();
  while (writer.matched_readers() < wait_readers && !g_stop) {
    if (since(wait_start) > wait_s) {
      std::fprintf(stderr,
                   "tessera replay: error: %d of %ld readers matched after %.1f s (--wait-s)\n",
                   writer.matched_readers(), wait_readers, wait_s);
      return 2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // The last batch of each robot says so (its agent then knows the robot is done).
  std::vector<std::size_t> last_of_robot(input.robots, 0);
  for (std::size_t k = 0; k < plan.batches.size(); ++k) last_of_robot[plan.batches[k].robot] = k;
  const auto start = std::chrono::steady_clock::now();
  std::size_t published = 0;
  for (std::size_t k = 0; k < plan.batches.size() && !g_stop; ++k) {
    const StreamBatch& b = plan.batches[k];
    const double wait = b.stamp - since(start);
    if (wait > 0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
    writer.publish(b, input.graph.d, last_of_robot[b.robot] == k);
    ++published;
  }
  const double play_s = since(start);
  writer.wait_acknowledged(10.0);
  std::printf(
      "replayed %zu of %zu batches (%zu poses, %zu measurements, %zu robots) in %.2f s "
      "onto %s, run %s, domain %ld\n",
      published, plan.batches.size(), input.graph.num_poses, plan.measurements, input.robots,
      play_s, transport::kGraphStreamTopic, run_id->c_str(), domain);
  if (auto json = args.get("json")) {
    cli::JsonObject j;
    j.add("graph", graph)
        .add("run_id", *run_id)
        .add("domain", domain)
        .add("robots", input.robots)
        .add("poses", input.graph.num_poses)
        .add("measurements", plan.measurements)
        .add("batches", plan.batches.size())
        .add("published", published)
        .add("rate", options.rate)
        .add("speedup", options.speedup)
        .add("planned_s", plan.duration_s)
        .add("play_s", play_s);
    cli::write_output(*json, j.str());
  }
  std::fflush(stdout);  // the summary is also the sign that the play is over
  const auto linger_start = std::chrono::steady_clock::now();
  while (!g_stop && since(linger_start) < linger_s)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return g_stop && published < plan.batches.size() ? 130 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const tessera::InputError& e) {
    std::fprintf(stderr, "tessera replay: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera replay: internal error: %s\n", e.what());
    return 3;
  }
}
