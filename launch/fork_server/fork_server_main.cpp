// tessera-fork-server: `tessera launch`'s way to start the coordinator and the N agents of a
// run on this host without each of them paying the dynamic loading of Fast DDS (and
// libcrypto, libsqlite3: BIND_NOW, ~40 ms of CPU per process; docs/dds-runtime.md, "Fork
// server"). This process is linked with the agent and coordinator code, so the loader
// relocates everything once here; then it forks one child per process of the run, and each
// child runs the entry function that tessera-agent's or tessera-coordinator's main() runs,
// with the argv launch would have exec'ed. It writes each child's pid to launch and exits, so
// the children are re-parented to launch (a child subreaper), which waits for them, signals
// them and judges their exit codes exactly as it does for exec'ed processes.
//
// Nothing of Fast DDS may exist before a fork (its threads would not survive it, its shared
// memory segments would be shared): this process only parses its argv and forks; the first
// Fast DDS object of each process is created by the entry function in the child. Each fork is
// refused unless this process is still single-threaded. Between the coordinator's fork and the
// first agent's, this process prepares plain data that every agent would otherwise build on
// its own while the coordinator partitions on both cores (prepare_agents): the agents' graph
// file, parsed once, and Fast DDS's TypeObjectFactory tables (no thread, no descriptor, no
// shared memory).
//
// usage (by launch): tessera-fork-server --spec-fd FD --title-room BLANKS
//   FD: a pipe from which the spec is read to its end (launch/fork_spec.hpp: serialize_fork_spec);
//   BLANKS: as many spaces as the longest child's command line, so that the argv area where
//   each child writes its own command line (ps, pgrep -f) is large enough.

#include <fastrtps/types/TypeObjectFactory.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "agent/agent_entry.hpp"
#include "agent/agent_options.hpp"
#include "coordinator/coordinator_entry.hpp"
#include "launch/fork_spec.hpp"
#include "launch/startup_batch.hpp"
#include "runtime/preloaded_graph.hpp"
#include "transport/fastdds/process_exit.hpp"

using namespace tessera;

namespace {

// Threads of this process (the "Threads:" line of /proc/self/status), -1 if unreadable.
int thread_count() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("Threads:", 0) == 0) return std::atoi(line.c_str() + 8);
  return -1;
}

// The whole of descriptor `fd` (read to its end), or throws InputError.
std::string read_all(int fd) {
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = read(fd, buf, sizeof(buf));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw InputError("fork server: cannot read the spec: " + std::string(std::strerror(errno)));
    if (n == 0) return text;
    text.append(buf, static_cast<std::size_t>(n));
  }
}

// The --graph every agent of `spec` reads (as the agent's own option parser reads it), or ""
// when they read different files (robot files) or an agent's options do not parse (that agent
// reports them itself).
std::string shared_agent_graph(const launch::ForkSpec& spec) {
  std::string shared;
  for (const launch::ForkChild& c : spec.children) {
    if (c.role != launch::ForkRole::kAgent) continue;
    std::string graph;
    try {
      graph = agent::parse_agent_options({c.argv.begin() + 1, c.argv.end()}).graph;
    } catch (const InputError&) {
      return "";
    }
    if (!shared.empty() && shared != graph) return "";
    shared = graph;
  }
  return shared;
}

// What every agent would otherwise do on its own at start-up, done once here so that the
// agents inherit it (copy-on-write pages they only read); measured ~3 ms of CPU per agent
// each, spent while the coordinator partitions on both cores (docs/dds-runtime.md, "Start-up"):
// - the shared graph file, parsed (core/runtime/preloaded_graph.hpp; a file that does not parse is
//   left to each agent, which reports it);
// - Fast DDS's TypeObjectFactory singleton (builtin types and annotations), which each
//   process otherwise builds when it announces its first endpoint. It is a table of type
//   descriptions: it starts no thread and opens nothing (checked with strace; the thread
//   count is checked again before every fork).
// Called after the coordinator's fork: that one is on the run's critical path.
void prepare_agents(const launch::ForkSpec& spec) {
  if (const std::string graph = shared_agent_graph(spec); !graph.empty())
    agent::preload_graph(graph);
  eprosima::fastrtps::types::TypeObjectFactory::get_instance();
}

// The memory holding this process's argv strings (contiguous on Linux): what ps and pgrep -f
// read as the command line.
struct ArgvArea {
  char* begin = nullptr;
  std::size_t size = 0;
};

// Shows `argv` as this process's command line and its program name as the thread name, so a
// forked child looks like the executable it stands for ("tessera-agent --graph ... --id 1
// ..."): operators and the tests find processes with pgrep -f. The area is the fork server's
// own argv, made large enough by launch (--title-room); it is padded with NULs (ps shows
// trailing blanks).
void show_as(const ArgvArea& area, const std::vector<std::string>& argv) {
  std::size_t at = 0;
  for (const std::string& a : argv) {
    const std::size_t n = std::min(a.size() + 1, area.size - at);
    std::memcpy(area.begin + at, a.c_str(), n);
    at += n;
    if (at == area.size) break;
  }
  if (area.size > 0) {
    std::memset(area.begin + at, 0, area.size - at);
    area.begin[area.size - 1] = '\0';
  }
  const std::string& exe = argv.front();
  const std::string name = exe.substr(exe.find_last_of('/') + 1);
  prctl(PR_SET_NAME, name.c_str(), 0, 0, 0);  // kernel keeps 15 characters
}

// Whether the coordinator partitions launch's file while the agents start (--graph), the only
// time it has work that their start-up slows down.
bool coordinator_partitions_file(const launch::ForkSpec& spec) {
  for (const launch::ForkChild& c : spec.children)
    if (c.role == launch::ForkRole::kCoordinator)
      return std::find(c.argv.begin(), c.argv.end(), "--graph") != c.argv.end();
  return false;
}

// Whether the agents start in SCHED_BATCH (launch/startup_batch.hpp): when launch asks (its
// default) and the coordinator partitions launch's file.
bool agents_batch_at_start(const launch::ForkSpec& spec) {
  return spec.agents_batch && coordinator_partitions_file(spec);
}

// The child's side of a fork: the same process set-up as launch's exec path
// (launch::enter_child_process), then the entry. `batch`: an agent starts in SCHED_BATCH.
[[noreturn]] void run_child(const launch::ForkSpec& spec, std::size_t k, const ArgvArea& area,
                            bool batch) {
  const launch::ForkChild& c = spec.children[k];
  launch::enter_child_process(c);
  // Before the entry creates any thread: every thread inherits this one's policy.
  if (batch && c.role == launch::ForkRole::kAgent) launch::enter_startup_batch();
  // Descriptors meant for launch or for another child: an agent holding launch's progress
  // pipe would keep it open after the coordinator has left.
  close(spec.pid_fd);
  for (const launch::ForkChild& other : spec.children)
    if (other.stdout_fd > 2) close(other.stdout_fd);
  std::vector<std::string> strings = c.argv;  // copies: the argv area is overwritten next
  show_as(area, strings);
  std::vector<char*> argv;
  for (auto& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(strings.size());
  const int code = c.role == launch::ForkRole::kCoordinator
                       ? coordinator::coordinator_main(argc, argv.data())
                       : agent::agent_main(argc, argv.data());
  transport::exit_process(code);
}

}  // namespace

int main(int argc, char** argv) {
  launch::ForkSpec spec;
  try {
    if (argc != 5 || std::strcmp(argv[1], "--spec-fd") != 0 ||
        std::strcmp(argv[3], "--title-room") != 0)
      throw InputError(
          "usage: tessera-fork-server --spec-fd FD --title-room BLANKS (run by tessera launch)");
    char* end = nullptr;
    const long fd = std::strtol(argv[2], &end, 10);
    if (*argv[2] == '\0' || *end != '\0' || fd < 0)
      throw InputError(std::string("--spec-fd '") + argv[2] + "' is not a descriptor");
    spec = launch::parse_fork_spec(read_all(static_cast<int>(fd)));
    close(static_cast<int>(fd));
    if (std::strlen(argv[4]) < launch::longest_command_line(spec))
      throw InputError("--title-room is shorter than the longest child's command line");
  } catch (const InputError& e) {
    std::fprintf(stderr, "tessera-fork-server: error: %s\n", e.what());
    return 2;
  }
  const ArgvArea area{argv[0], static_cast<std::size_t>(argv[argc - 1] +
                                                        std::strlen(argv[argc - 1]) + 1 - argv[0])};
  const bool batch = agents_batch_at_start(spec);
  bool prepared = false;
  for (std::size_t k = 0; k < spec.children.size(); ++k) {
    if (!prepared && spec.children[k].role == launch::ForkRole::kAgent) {
      prepare_agents(spec);
      prepared = true;
    }
    const int threads = thread_count();
    if (threads != 1) {
      std::fprintf(stderr,
                   "tessera-fork-server: error: %d threads before forking child %zu (must be 1: "
                   "nothing of Fast DDS may run before a fork)\n",
                   threads, k);
      return 1;
    }
    std::fflush(nullptr);  // nothing buffered may be written twice
    const pid_t pid = fork();
    if (pid < 0) {
      std::fprintf(stderr, "tessera-fork-server: error: fork failed: %s\n", std::strerror(errno));
      return 1;
    }
    if (pid == 0) run_child(spec, k, area, batch);
    const std::string line = std::to_string(pid) + "\n";
    if (write(spec.pid_fd, line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
      std::fprintf(stderr, "tessera-fork-server: error: cannot report pid %d to launch\n",
                   static_cast<int>(pid));
      return 1;
    }
  }
  close(spec.pid_fd);
  transport::exit_process(0);
}
