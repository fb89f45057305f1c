#pragma once
// What `tessera launch` asks its fork server (tessera-fork-server, launch/fork_server/) to start:
// the coordinator and the agents, each with the argv its standalone executable would get.
// Plain data and a flat encoding, free of Fast DDS, so that `tessera` (which never links
// Fast DDS) can write it and the fork server read it back. It goes through a pipe, not the
// server's command line: while the server loads, its command line must not look like an
// agent's to `pgrep -f 'tessera-agent.*--id 1 ...'` (tests and operators find processes so).

#include <string>
#include <vector>

namespace tessera::launch {

/// Which entry function a forked child runs (the one the standalone executable's main calls).
enum class ForkRole { kCoordinator, kAgent };

/// One process to start.
struct ForkChild {
  ForkRole role = ForkRole::kAgent;
  /// File for its stderr (and its stdout when stdout_fd < 0); created or truncated.
  std::string log;
  /// An inherited descriptor to use as its stdout (launch's progress pipe), or -1.
  int stdout_fd = -1;
  /// Its argv, argv[0] first (the standalone executable's path: what ps shows).
  std::vector<std::string> argv;
};

/// Everything the fork server needs.
struct ForkSpec {
  /// Inherited descriptor on which the server writes one line "<pid>\n" per child, in order.
  int pid_fd = -1;
  std::vector<ForkChild> children;
  /// The agents start with every thread in SCHED_BATCH when the coordinator partitions
  /// launch's file while they start, until their assignment (launch/startup_batch.hpp; launch's
  /// default, --no-agents-batch turns it off).
  bool agents_batch = false;

  /// Throws InputError naming the bad field: pid_fd < 0, no children, a child without argv
  /// or log, or a stdout_fd < -1.
  void validate() const;
};

/// The spec as a list of strings: "--pid-fd FD", "--agents-batch" when set, then, per child,
/// "--child ROLE LOG STDOUT_FD ARGC ARGV...". Validates `spec` first.
std::vector<std::string> encode_fork_spec(const ForkSpec& spec);

/// Inverse of encode_fork_spec(); throws InputError naming the bad item on malformed input.
ForkSpec decode_fork_spec(const std::vector<std::string>& args);

/// encode_fork_spec() as one byte string, each item NUL-terminated (what goes down the pipe).
/// Throws InputError when an item contains a NUL byte.
std::string serialize_fork_spec(const ForkSpec& spec);

/// Inverse of serialize_fork_spec(); throws InputError on malformed input (also when the
/// text does not end with a NUL, i.e. was cut short).
ForkSpec parse_fork_spec(const std::string& text);

/// Bytes of the longest child's command line (its argv, each NUL-terminated): the room the
/// fork server's own argv must offer for a child to show its command line in place of it.
std::size_t longest_command_line(const ForkSpec& spec);

const char* fork_role_name(ForkRole role);

/// Called in a freshly forked child (exec'ed by launch or forked by the fork server, so both
/// paths give a child the same process): its own process group (a terminal's Ctrl-C reaches
/// launch only, which decides how to stop the run; the coordinator's is in a session of its
/// own, i.e. its own autogroup for the scheduler), default SIGINT / SIGTERM, stdout to
/// `child.stdout_fd` (or the log) and stderr to `child.log`, created or truncated.
void enter_child_process(const ForkChild& child);

}  // namespace tessera::launch
