#pragma once
// The processes of a `tessera launch` run (the coordinator and the agents) as launch sees
// them: started either by exec'ing tessera-coordinator / tessera-agent, or through the fork
// server (launch/fork_server/: the libraries are loaded once and each process is a fork of it),
// and in both cases direct children of launch afterwards, so waiting, signalling and the exit
// codes are the same.

#include <string>
#include <vector>

#include "launch/fork_spec.hpp"

namespace tessera::launch {

/// One process of the run.
struct Child {
  std::string name;  ///< "coordinator" or "agent K", for launch's messages.
  pid_t pid = -1;
  std::string log;
  bool running = false;
  int code = -1;        ///< exit code, or 128 + signal
  long agent = -1;      ///< agent id; -1 for the coordinator
  bool judged = false;  ///< its end has been judged (launch_loss_policy.hpp)
  bool lost = false;    ///< it died and the run went on without it
};

/// Starts every process of `spec` with execv (argv[0] is the executable), each in its own
/// process group with default SIGINT/SIGTERM, stdout to its stdout_fd or its log, stderr to
/// its log. `names` and `agents` label them (same order as spec.children; spec.pid_fd unused).
std::vector<Child> spawn_exec(const ForkSpec& spec, const std::vector<std::string>& names,
                              const std::vector<long>& agents);

/// The same processes started by `fork_server` (the tessera-fork-server executable), which
/// forks them and exits; launch becomes their parent (it is made a child subreaper for the
/// time of the start-up), so the result is used exactly like spawn_exec()'s. `server_log`
/// receives the server's own output. Throws std::runtime_error (with the log's tail) when the
/// server fails or does not report every pid within `timeout_s`; processes it had already
/// started are killed then.
std::vector<Child> spawn_forked(const std::string& fork_server, ForkSpec spec,
                                const std::vector<std::string>& names,
                                const std::vector<long>& agents, const std::string& server_log,
                                double timeout_s);

/// Reaps the children that have ended (waiting for all of them when `block`).
void reap(std::vector<Child>& children, bool block);

bool any_running(const std::vector<Child>& children);

/// Asks every process to stop (they shut down cleanly on SIGINT), SIGKILLs what is left after
/// `grace_s` and says so on stderr, naming each one: a SIGKILLed process cannot remove its Fast
/// DDS shared-memory files, so the message tells the user where leftovers come from.
void stop_all(std::vector<Child>& children, double grace_s);

/// The last `max_lines` lines of a log, indented, for error messages.
std::string tail_of(const std::string& path, std::size_t max_lines);

/// The lines of the log at `path` that are notes ("<tag>: note: ..."), each as one line: a
/// finished run's logs are removed, and a note (e.g. a Fast DDS abort covered at the end of the
/// run, transport/fastdds/teardown_guard.hpp) should still be seen.
std::vector<std::string> notes_of(const std::string& path);

}  // namespace tessera::launch
