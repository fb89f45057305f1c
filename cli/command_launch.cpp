// `tessera launch`: runs a whole distributed solve on this host as separate processes, the
// coordinator and N agents talking over DDS (tessera-coordinator / tessera-agent, found next
// to this executable). Streams the coordinator's progress, prints the summary, and takes
// everything down on the first failure, on the time limit and on Ctrl-C.

#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "arguments.hpp"
#include "commands.hpp"
#include "huge_page_heaps.hpp"
#include "launch_children.hpp"
#include "launch_loss_policy.hpp"
#include "launch_transport.hpp"
#include "robot_files.hpp"
#include "runtime/progress_lines.hpp"
#include "session_args.hpp"
#include "shm_leftovers.hpp"
#include "transport/run_identity.hpp"
#include "transport/security.hpp"

namespace tessera::cli {

namespace {

// %s: the loss options (launch_loss_policy.hpp), then the shared DDS session options
// (session_args.hpp).
constexpr const char* kHelp =
    R"(usage: tessera launch [GRAPH.g2o | ROBOT_FILES_DIR | R0.g2o,R1.g2o,...] --agents N [options]

Runs a distributed solve on this host as separate processes: one tessera-coordinator and N
tessera-agent processes (robot k reads its sequential share of GRAPH, or the k-th robot file
of a folder or list, as written by tessera generate --split) talking peer to peer
over Fast DDS. Prints progress (round, cost, gradient norm) while it runs and the JSON
summary at the end. Any failing process (a dead agent only with --on-agent-loss stop, the
default), the time limit or Ctrl-C stops every process; the exit code is then non-zero.
Without GRAPH, a 3D grid is generated into a temporary folder
(tessera generate --kind grid3d --poses P --robots N). The agents initialise like
`tessera solve` (--init, default chordal), so both give the same iterates.

options:
  --agents N           number of agent processes, 1..64                     [3]
  --algorithm NAME     rbcd | rbcd++ | irbcd                                 [irbcd]
  --partition PRESET   sequential | fast | eco | strong | highest           [highest]
  --init NAME          chordal | distributed | file (VERTEX poses)           [chordal]
  --grad-tol X         stop when the gradient norm is at most X (> 0)       [0.01]
  --max-rounds K       round limit (0 = the solver's default, 10000)        [0]
  --rank R             relaxation rank (0 = the solver's default, 5)        [0]
  --seed S             solver seed                                           [1]
  --certify            after the solve, the agents certify global optimality distributedly
                       and escape saddles up the staircase (default: on)
  --no-certify         skip the certificate
  --status-relay       round statuses through agent 0, one bundle per step instead of
                       all to all (fewer DDS deliveries, one more hop; not with
                       --on-agent-loss continue; docs/dds-runtime.md, "Session 9";
                       the default)
  --no-status-relay    round statuses all to all (every agent to every agent)
  --json FILE          also write the summary to FILE
  --out FILE           write the merged poses (g2o, VERTEX lines)
  --tum FILE           write the merged poses (TUM)
  --timeout S          time limit of the whole run, seconds                 [600]
  --poses P            poses of the generated graph (without GRAPH)         [1000]
  --status-interval S  coordinator status line (agents alive, rounds, lagging or lost
                       agents) every S seconds and on changes; 0 = off          [5]
  --progress-interval S  at most one progress line per S seconds besides the first,
                       the restarts and the last; 0 = every round the coordinator
                       sees (every round with replicas or rejoin)             [0.1]
  --no-fork-server     start tessera-coordinator and tessera-agent with exec, each
                       loading Fast DDS itself (default: one tessera-fork-server loads it
                       once and forks them; see docs/dds-runtime.md, "Fork server")
  --agents-yield       the agents start at nice 19 (threads, or their own autogroup)
                       until their assignment, so that the coordinator's partition of
                       GRAPH gets the CPU first (fork server and a whole file only; off:
                       measured no gain on a loaded host, docs/dds-runtime.md, start9)
  --no-agents-batch    the agents start as normal threads (default: SCHED_BATCH until
                       their assignment, so that their start-up's wake-ups do not preempt
                       the coordinator's partition of GRAPH; fork server and a whole file
                       only; docs/dds-runtime.md, start13)
%s  --quiet              no progress lines
  --help               this text

DDS session options (passed on to the coordinator and every agent):
%s
exit codes: 0 done, 1 the run failed (a process failed, or the time limit), 2 bad options,
130 interrupted.
)";

volatile sig_atomic_t g_signal = 0;
void on_signal(int signo) {
  g_signal = signo;
}

std::string self_dir() {
  char buf[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return ".";
  std::string p(buf, static_cast<std::size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}

// In process (no `sh -c rm -rf`: two more process starts at the end of every run).
void remove_tree(const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  if (ec)
    std::fprintf(stderr, "tessera launch: could not remove %s: %s\n", dir.c_str(),
                 ec.message().c_str());
}

// Prints the coordinator's JSON summary (launch's main output). Returns whether it was read.
bool print_summary(const std::string& path) {
  std::ifstream in(path);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  std::printf("summary:\n%s", ss.str().c_str());
  std::fflush(stdout);
  return true;
}

// Removes the shared-memory files of dead processes of `domain` (and the listed dead segments)
// and says so on stderr; `when` completes the sentence ("before the run", ...).
void remove_dead_files_of(int domain, std::set<std::string> segments, const char* when) {
  ShmCleanupOptions shm;
  shm.domain = domain;
  shm.segments = std::move(segments);
  const ShmCleanupResult r = remove_dead_shm_files(shm);
  if (!r.removed.empty())
    std::fprintf(stderr,
                 "tessera launch: removed %zu shared-memory files of dead processes of domain %d "
                 "from /dev/shm %s\n",
                 r.removed.size(), domain, when);
}

}  // namespace

int run_launch(const Args& argv) {
  for (const auto& a : argv)
    if (a == "--help" || a == "-h") {
      std::printf(kHelp, launch_loss_help().c_str(),
                  session_options_help(SessionArgsFor::kLaunch).c_str());
      return 0;
    }
  std::set<std::string> valued = {"agents",
                                  "algorithm",
                                  "partition",
                                  "init",
                                  "grad-tol",
                                  "max-rounds",
                                  "rank",
                                  "seed",
                                  "json",
                                  "out",
                                  "tum",
                                  "timeout",
                                  "poses",
                                  "status-interval",
                                  "progress-interval"};
  for (const auto& n : launch_loss_option_names()) valued.insert(n);
  Arguments args(argv, with_session_options(valued, SessionArgsFor::kLaunch),
                 {"quiet", "certify", "no-certify", "no-fork-server", "agents-yield",
                  "no-agents-batch", "status-relay", "no-status-relay"});
  if (args.positional().size() > 1)
    throw InputError("launch: at most one GRAPH argument, got " +
                     std::to_string(args.positional().size()));
  // GRAPH may be one robot's own file per agent: a folder of *.g2o or a comma-separated list.
  const std::vector<std::string> robot_files =
      args.positional().empty() ? std::vector<std::string>{} : robot_files_of(args.positional()[0]);
  const long agents =
      args.get_long("agents", robot_files.empty() ? 3 : static_cast<long>(robot_files.size()));
  if (!robot_files.empty() && static_cast<std::size_t>(agents) != robot_files.size())
    throw InputError("launch: " + std::to_string(robot_files.size()) + " robot files in " +
                     args.positional()[0] + " but --agents " + std::to_string(agents));
  if (agents < 1 || agents > 64) throw InputError("launch: --agents must be in 1..64");
  const double status_interval = args.get_double("status-interval", 5);
  if (!(status_interval >= 0 && status_interval <= 86400))
    throw InputError("launch: --status-interval must be in 0..86400 seconds");
  const double progress_interval = args.get_double("progress-interval", 0.1);
  if (!(progress_interval >= 0 && progress_interval <= 3600))
    throw InputError("launch: --progress-interval must be in 0..3600 seconds");
  const std::string algorithm = args.get_or("algorithm", "irbcd");
  if (algorithm != "rbcd" && algorithm != "rbcd++" && algorithm != "irbcd")
    throw InputError("launch: --algorithm '" + algorithm + "' is not one of rbcd, rbcd++, irbcd");
  const std::string partition = args.get_or("partition", "highest");
  const std::string init = args.get_or("init", init_name(DistributedOptions{}.initialization));
  parse_init(init);  // InputError naming the valid ones
  const double grad_tol = args.get_double("grad-tol", 0.01);
  if (!(grad_tol > 0)) throw InputError("launch: --grad-tol must be > 0");
  const long max_rounds = args.get_long("max-rounds", 0);
  if (max_rounds < 0) throw InputError("launch: --max-rounds must be >= 0");
  const long rank = args.get_long("rank", 0);
  if (rank < 0) throw InputError("launch: --rank must be >= 0");
  const long seed = args.get_long("seed", 1);
  if (seed < 0) throw InputError("launch: --seed must be >= 0");
  SessionArgs net = parse_session_args(args, SessionArgsFor::kLaunch);
  if (!net.session.security_dir.empty())  // every identity is needed on this host
    for (long k = -1; k < agents; ++k)
      transport::security_files(net.session.security_dir,
                                transport::security_identity(k < 0, static_cast<std::uint32_t>(k)));
  const double timeout_s = args.get_double("timeout", 600);
  if (!(timeout_s > 0)) throw InputError("launch: --timeout must be > 0");
  const long poses = args.get_long("poses", 1000);
  if (poses < agents) throw InputError("launch: --poses must be at least --agents");
  const bool quiet = args.has("quiet");
  const LaunchLossOptions loss = parse_launch_loss_options(args);
  if (!args.has("transport")) net.session.transport = launch_transport(net.session, loss);

  const std::string bin = self_dir();
  for (const char* exe : {"tessera-agent", "tessera-coordinator"})
    if (access((bin + "/" + exe).c_str(), X_OK) != 0)
      throw InputError("launch: " + bin + "/" + exe + " not found (build it next to tessera)");
  const std::string fork_server = bin + "/tessera-fork-server";
  bool use_fork_server = !args.has("no-fork-server");
  if (use_fork_server && access(fork_server.c_str(), X_OK) != 0) {
    std::fprintf(stderr, "tessera launch: %s not found: starting the processes with exec\n",
                 fork_server.c_str());
    use_fork_server = false;
  }

  char tmpl[] = "/tmp/tessera-launch-XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error("launch: cannot create a temporary folder");
  const std::string work = tmpl;
  struct Cleanup {
    std::string dir;
    ~Cleanup() { remove_tree(dir); }
  } cleanup{work};

  std::string graph;
  if (args.positional().empty()) {
    graph = work + "/grid3d.g2o";
    std::string cmd = "'" + bin + "/tessera' generate --kind grid3d --poses " +
                      std::to_string(poses) + " --robots " + std::to_string(agents) + " --out '" +
                      graph + "' > '" + work + "/generate.log' 2>&1";
    if (std::system(cmd.c_str()) != 0)
      throw std::runtime_error("launch: generating the graph failed:\n" +
                               tail_of(work + "/generate.log", 10));
    std::printf("generated %s (grid3d, %ld poses, %ld robots)\n", graph.c_str(), poses, agents);
  } else {
    graph = args.positional()[0];
    for (const std::string& f : robot_files.empty() ? std::vector<std::string>{graph} : robot_files)
      if (!std::ifstream(f)) throw InputError(f, 0, "cannot open the graph");
  }
  const std::string summary = args.get_or("json", work + "/summary.json");
  if (!args.has("run-id"))
    net.session.run_id =
        "launch-" + std::to_string(getpid()) + "-" +
        std::to_string(std::chrono::steady_clock::now().time_since_epoch().count() % 1000000);
  const std::string& run_id = net.session.run_id;
  const std::vector<std::string> common = session_argv(net.session);

  // Our own handlers: a Ctrl-C stops the children cleanly instead of orphaning them.
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);
  g_signal = 0;

  int pipefd[2];
  if (pipe(pipefd) != 0) throw std::runtime_error("launch: pipe failed");
  fcntl(pipefd[0], F_SETFD, FD_CLOEXEC);  // the read end is ours alone
  std::vector<std::string> cargs = {bin + "/tessera-coordinator",
                                    "--agents",
                                    std::to_string(agents),
                                    "--partition",
                                    partition,
                                    "--algorithm",
                                    algorithm,
                                    "--init",
                                    init,
                                    "--grad-tol",
                                    args.get_or("grad-tol", "0.01"),
                                    "--max-rounds",
                                    std::to_string(max_rounds),
                                    "--rank",
                                    std::to_string(rank),
                                    "--seed",
                                    std::to_string(seed),
                                    "--partition-seed",  // `tessera solve` partitions with --seed
                                    std::to_string(seed),
                                    "--summary",
                                    summary,
                                    "--graph-name",
                                    graph.substr(graph.find_last_of('/') + 1),
                                    "--run-timeout",
                                    std::to_string(timeout_s),
                                    "--progress"};
  if (args.has("certify") && args.has("no-certify"))
    throw InputError("launch: --certify and --no-certify exclude each other");
  if (!args.has("no-certify")) cargs.push_back("--certify");
  if (args.has("status-relay") && args.has("no-status-relay"))
    throw InputError("launch: --status-relay and --no-status-relay exclude each other");
  // The coordinator relays by default (docs/dds-runtime.md, "Session 10").
  if (args.has("no-status-relay")) cargs.push_back("--no-status-relay");
  // Every process runs here and the coordinator can read the whole file: it partitions the
  // file's structure while the agents start up (coordinator/file_partition.hpp). Robot files
  // are each robot's own: there the announcements are the only whole structure.
  if (robot_files.empty()) cargs.insert(cargs.end(), {"--graph", graph});
  cargs.insert(cargs.end(), common.begin(), common.end());
  for (const auto& a : coordinator_loss_argv(loss)) cargs.push_back(a);
  if (args.has("out")) cargs.insert(cargs.end(), {"--output", args.get_or("out", "")});
  if (args.has("tum")) cargs.insert(cargs.end(), {"--tum", args.get_or("tum", "")});
  if (args.has("status-interval"))
    cargs.insert(cargs.end(), {"--status-interval", std::to_string(status_interval)});
  if (args.has("progress-interval"))
    cargs.insert(cargs.end(), {"--progress-interval", std::to_string(progress_interval)});

  // The processes to start, in order: the coordinator (stdout = our progress pipe), then
  // agents 0..N-1.
  ForkSpec spec;
  if (args.has("agents-yield")) spec.agents_nice = 19;  // agent/startup_priority.hpp
  spec.agents_batch = !args.has("no-agents-batch");     // agent/startup_batch.hpp
  std::vector<std::string> names = {"coordinator"};
  std::vector<long> agent_ids = {-1};
  spec.children.push_back(
      {ForkRole::kCoordinator, work + "/coordinator.log", pipefd[1], std::move(cargs)});
  for (long k = 0; k < agents; ++k) {
    std::vector<std::string> a = {
        bin + "/tessera-agent",
        "--graph",
        robot_files.empty() ? graph : robot_files[static_cast<std::size_t>(k)],
        "--robots",
        std::to_string(agents),
        "--id",
        std::to_string(k)};
    a.insert(a.end(), common.begin(), common.end());
    for (const auto& x : agent_loss_argv(loss)) a.push_back(x);
    spec.children.push_back(
        {ForkRole::kAgent, work + "/agent" + std::to_string(k) + ".log", -1, std::move(a)});
    names.push_back("agent " + std::to_string(k));
    agent_ids.push_back(k);
  }

  // Ports of this domain that dead processes of an earlier run left (a SIGKILLed agent started by
  // hand, an abort inside Fast DDS) can keep this run's participants from discovering each other
  // (seen in session 13: every later launch on that domain failed until they were removed). Only
  // files no live process holds or maps go (shm_leftovers.hpp).
  const int run_domain =
      net.session.domain >= 0 ? net.session.domain : transport::domain_for_run(run_id);
  remove_dead_files_of(run_domain, {}, "before the run");

  request_huge_page_heaps();  // for the processes started next (huge_page_heaps.hpp)
  const auto t0 = std::chrono::steady_clock::now();
  // Both close our copy of the progress pipe's write end once the coordinator has its own.
  std::vector<Child> children =
      use_fork_server ? spawn_forked(fork_server, spec, names, agent_ids, work + "/fork-server.log",
                                     std::min(timeout_s, 60.0))
                      : spawn_exec(spec, names, agent_ids);
  std::printf("launched run %s: coordinator + %ld agents, %s (logs in %s until the end)\n",
              run_id.c_str(), agents,
              use_fork_server ? "forked by tessera-fork-server" : "each exec'ed", work.c_str());
  std::fflush(stdout);

  // Data segments the run's processes mapped when one of them had failed: a killed process
  // cannot remove its own, and only its peers' maps tell its segment apart (shm_leftovers.hpp).
  std::set<std::string> run_segments;
  auto note_segments = [&] {
    std::vector<pid_t> pids;
    for (const auto& c : children)
      if (c.running) pids.push_back(c.pid);
    const auto mapped = mapped_segments(pids);
    run_segments.insert(mapped.begin(), mapped.end());
  };

  // Stream progress; watch for failures, the time limit and signals.
  std::string pending;
  bool summary_printed = false;
  bool guard_ended = false;  // a process ended through a teardown guard (its note)
  std::string failure;
  int exit_code = 0;
  bool pipe_open = true;
  for (;;) {
    if (pipe_open) {
      pollfd pfd{pipefd[0], POLLIN, 0};
      if (poll(&pfd, 1, 50) > 0) {
        char buf[4096];
        const ssize_t n = read(pipefd[0], buf, sizeof(buf));
        if (n <= 0) {
          pipe_open = false;
        } else {
          pending.append(buf, static_cast<std::size_t>(n));
          for (std::size_t nl; (nl = pending.find('\n')) != std::string::npos;) {
            const std::string line = pending.substr(0, nl);
            pending.erase(0, nl + 1);
            if (line == coordinator::kSummaryWrittenLine) {
              // The result is known: show it now, not after every process has left.
              summary_printed = print_summary(summary);
              continue;
            }
            if (!quiet) std::printf("%s\n", line.c_str());
          }
          std::fflush(stdout);
        }
      }
    } else {
      usleep(5000);  // the end of a run: the agents' exits are reaped within 5 ms
    }
    reap(children, false);
    if (g_signal) {
      failure = std::string("interrupted (") + (g_signal == SIGINT ? "SIGINT" : "SIGTERM") +
                "): stopping every process";
      exit_code = 130;
      break;
    }
    const bool coordinator_done = !children[0].running && children[0].code == 0;
    for (auto& c : children) {
      if (c.running || c.judged) continue;
      c.judged = true;
      // A note means a teardown guard ended it (transport/teardown_guard.hpp): with its code,
      // but from inside Fast DDS, so its files stay like a failed process's.
      if (!notes_of(c.log).empty()) guard_ended = true;
      if (c.code != 0 || guard_ended) note_segments();
      const ExitVerdict v = judge_exit(loss, c.agent, c.code, coordinator_done);
      c.lost = v.lost;
      if (!v.notice.empty()) std::fprintf(stderr, "tessera launch: %s\n", v.notice.c_str());
      if (!v.failure.empty() && failure.empty()) {
        failure = v.failure;
        exit_code = 1;
      }
    }
    if (!failure.empty()) break;
    if (!any_running(children)) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s) {
      failure = "time limit of " + std::to_string(timeout_s) + " s reached";
      exit_code = 1;
      break;
    }
  }
  close(pipefd[0]);
  if (!failure.empty()) {
    std::fprintf(stderr, "tessera launch: %s\n", failure.c_str());
    // The others notice a lost or aborting peer themselves (within ~2 s): give them time to
    // stop on their own and say why, then ask (SIGINT) and finally force (SIGKILL).
    if (exit_code != 130) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
      while (any_running(children) && std::chrono::steady_clock::now() < until) {
        reap(children, false);
        usleep(20000);
      }
    }
    note_segments();  // stop_all may have to SIGKILL some of them
    stop_all(children, exit_code == 130 ? 5.0 : 3.0);
    for (const auto& c : children)
      if (c.code != 0 && c.code != 130 && c.code != 143)
        std::fprintf(stderr, "  %s (exit %d):\n%s", c.name.c_str(), c.code,
                     tail_of(c.log, 6).c_str());
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  // Every process has ended. One that failed may have been killed (SIGKILL, an abort) and left
  // its shared-memory files: remove what of this run's domain no live process holds.
  bool any_failed = guard_ended;
  for (const auto& c : children) any_failed = any_failed || c.code != 0;
  if (any_failed) remove_dead_files_of(run_domain, std::move(run_segments), "after the run");
  if (!failure.empty()) return exit_code;

  if (!summary_printed) print_summary(summary);
  for (const auto& c : children)
    for (const auto& note : notes_of(c.log))
      std::fprintf(stderr, "tessera launch: %s: %s\n", c.name.c_str(), note.c_str());
  std::string lost;
  for (const auto& c : children)
    if (c.lost) lost += (lost.empty() ? "" : ", ") + c.name;
  if (!lost.empty())
    std::printf(
        "finished without %s (lost during the run; its block was re-partitioned among "
        "the survivors: see \"fault\" in the summary)\n",
        lost.c_str());
  std::printf("wall time %.2f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace tessera::cli
