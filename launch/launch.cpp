#include "launch/launch.hpp"

#include <fcntl.h>
#include <limits.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <tessera/util/input_error.hpp>

#include "launch/dpgo_csv_input.hpp"
#include "launch/free_domain.hpp"
#include "launch/launch_argv.hpp"
#include "launch/launch_children.hpp"
#include "launch/launch_transport.hpp"
#include "launch/run_cleanup.hpp"
#include "launch/supervision.hpp"
#include "transport/fastdds/shm_segment_keeper.hpp"
#include "transport/run_identity.hpp"

namespace tessera::launch {

std::string running_program_dir() {
  char buf[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return ".";
  std::string p(buf, static_cast<std::size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}

namespace {

// Whether the fork server is used: asked for and present (else exec, with a word on stderr).
bool use_fork_server(const LaunchOptions& o, const std::string& fork_server) {
  if (!o.fork_server) return false;
  if (access(fork_server.c_str(), X_OK) == 0) return true;
  std::fprintf(stderr, "tessera launch: %s not found: starting the processes with exec\n",
               fork_server.c_str());
  return false;
}

// The graph the run reads: the given one (each file must open), or a generated grid3d.
std::string prepare_graph(const LaunchOptions& o, const std::string& bin, const std::string& work) {
  if (!o.graph.empty()) {
    const std::vector<std::string> files = o.robot_files();
    for (const std::string& f : files.empty() ? std::vector<std::string>{o.graph} : files)
      if (!std::ifstream(f)) throw InputError(f, 0, "cannot open the graph");
    return o.graph;
  }
  const std::string graph = work + "/grid3d.g2o";
  const std::string cmd = "'" + bin + "/tessera' generate --kind grid3d --poses " +
                          std::to_string(o.poses) + " --robots " + std::to_string(o.agents) +
                          " --out '" + graph + "' > '" + work + "/generate.log' 2>&1";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("launch: generating the graph failed:\n" +
                             tail_of(work + "/generate.log", 10));
  std::printf("generated %s (grid3d, %ld poses, %ld robots)\n", graph.c_str(), o.poses, o.agents);
  return graph;
}

// The run's own id: launch's pid and a clock reading, so that two launches never share one.
std::string fresh_run_id() {
  return "launch-" + std::to_string(getpid()) + "-" +
         std::to_string(std::chrono::steady_clock::now().time_since_epoch().count() % 1000000);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

LaunchResult launch(LaunchOptions o) {
  o.validate();
  const auto team = static_cast<std::uint32_t>(o.agents);
  if (o.choose_transport) o.net.session.transport = launch_transport(o.net.session, o.loss, team);
  o.net.session.lease_s = launch_lease_s(o.net.session.lease_s, !o.choose_lease, team);
  const std::string bin = o.bin_dir.empty() ? running_program_dir() : o.bin_dir;
  for (const char* exe : {"tessera-agent", "tessera-coordinator"})
    if (access((bin + "/" + exe).c_str(), X_OK) != 0)
      throw InputError("launch: " + bin + "/" + exe + " not found (build it next to tessera)");
  const std::string fork_server = bin + "/tessera-fork-server";
  const bool forked = use_fork_server(o, fork_server);

  const WorkDir work(o.keep_logs);
  // A dpgo CSV: the robots' g2o files, one agent each.
  if (const std::string dir = dpgo_csv_as_robot_files(o.graph, o.agents, work.path()); !dir.empty())
    o.graph = dir;
  RunPaths paths;
  paths.bin = bin;
  paths.work = work.path();
  paths.graph = prepare_graph(o, bin, work.path());
  paths.summary = o.json.empty() ? work.path() + "/summary.json" : o.json;
  if (o.net.session.run_id.empty()) o.net.session.run_id = fresh_run_id();
  LaunchResult result;
  result.run_id = o.net.session.run_id;

  SupervisionOutcome outcome;
  std::vector<Child> children;
  std::chrono::steady_clock::time_point t0;
  // Ports of this domain that dead processes of an earlier run left (a SIGKILLed agent started by
  // hand, an abort inside Fast DDS) can keep this run's participants from discovering each other
  // (every later launch on that domain failed until they were removed). Only files no live
  // process holds or maps go (transport/fastdds/shm_leftovers.hpp).
  // Without --domain: the run id's domain, or the next one no live participant is on
  // (free_domain.hpp); every process is then told it.
  if (o.net.session.domain < 0) {
    const int derived = transport::domain_for_run(result.run_id);
    o.net.session.domain = free_domain_from(derived);
    if (o.net.session.domain != derived && !o.quiet)
      std::printf("domain %d is in use by another run: this run uses domain %d\n", derived,
                  o.net.session.domain);
  }
  const int run_domain = o.net.session.domain;
  {
    const StopSignals signals;
    int pipefd[2];
    if (pipe(pipefd) != 0) throw std::runtime_error("launch: pipe failed");
    fcntl(pipefd[0], F_SETFD, FD_CLOEXEC);  // the read end is ours alone
    const ProcessPlan plan = plan_processes(o, paths, pipefd[1]);
    remove_dead_files_of(run_domain, {}, "before the run");

    // The children inherit this process's environment, and with it the heaps' page size that
    // `tessera launch` chose before (launch/heap_pages.hpp).
    t0 = std::chrono::steady_clock::now();
    // Both close our copy of the progress pipe's write end once the coordinator has its own.
    children = forked ? spawn_forked(fork_server, plan.spec, plan.names, plan.agent_ids,
                                     work.path() + "/fork-server.log", std::min(o.timeout_s, 60.0))
                      : spawn_exec(plan.spec, plan.names, plan.agent_ids);
    std::printf("launched run %s: coordinator + %ld agents, %s (logs in %s%s)\n",
                result.run_id.c_str(), o.agents,
                forked ? "forked by tessera-fork-server" : "each exec'ed", work.path().c_str(),
                o.keep_logs.empty() ? " until the end" : "");
    std::fflush(stdout);

    SupervisionOptions watch;
    watch.progress_fd = pipefd[0];
    watch.summary = paths.summary;
    watch.quiet = o.quiet;
    watch.timeout_s = o.timeout_s;
    watch.start = t0;
    watch.loss = o.loss;
    outcome = supervise(children, watch);
  }
  // Every process has ended. One that failed may have been killed (SIGKILL, an abort) and left
  // its shared-memory files: remove what of this run's domain no live process holds.
  bool any_failed = outcome.guard_ended;
  for (const auto& c : children) any_failed = any_failed || c.code != 0;
  if (any_failed)
    remove_dead_files_of(run_domain, std::move(outcome.run_segments), "after the run");
  // The shared-memory segments this run's processes kept readable for late readers after
  // deleting their participants (transport/fastdds/shm_segment_keeper.hpp): nobody of the run
  // is left to read them.
  std::vector<int> pids;
  for (const auto& c : children) pids.push_back(static_cast<int>(c.pid));
  transport::sweep_kept_segments("/dev/shm", transport::kKeptSegmentLifeS, pids);
  result.exit_code = outcome.exit_code;
  result.failure = outcome.failure;
  result.summary_json = outcome.summary;
  if (!outcome.failure.empty()) {
    result.wall_s = seconds_since(t0);
    return result;
  }

  if (!outcome.summary_printed)
    if (const auto text = read_summary(paths.summary)) {
      print_summary(*text);
      result.summary_json = *text;
    }
  for (const auto& c : children)
    for (const auto& note : notes_of(c.log)) {
      std::fprintf(stderr, "tessera launch: %s: %s\n", c.name.c_str(), note.c_str());
      result.notes.push_back(c.name + ": " + note);
    }
  std::string lost;
  for (const auto& c : children)
    if (c.lost) {
      lost += (lost.empty() ? "" : ", ") + c.name;
      result.lost.push_back(c.name);
    }
  if (!lost.empty())
    std::printf(
        "finished without %s (lost during the run; its block was re-partitioned among "
        "the survivors: see \"fault\" in the summary)\n",
        lost.c_str());
  result.wall_s = seconds_since(t0);
  std::printf("wall time %.2f s\n", result.wall_s);
  return result;
}

}  // namespace tessera::launch
