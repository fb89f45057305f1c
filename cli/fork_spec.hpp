#pragma once
// What `tessera launch` asks its fork server (tessera-fork-server, cli/fork_server/) to start:
// the coordinator and the agents, each with the argv its standalone executable would get.
// Plain data and a flat argv encoding, free of Fast DDS, so that `tessera` (which never links
// Fast DDS) can write it and the fork server read it back. Passing it on the fork server's
// own command line also gives the server an argv area large enough to show each child's
// command line in place of its own (ps / pgrep -f see "tessera-agent ... --id 1 ...").

#include <string>
#include <vector>

namespace tessera::cli {

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

  /// Throws InputError naming the bad field: pid_fd < 0, no children, a child without argv
  /// or log, or a stdout_fd < -1.
  void validate() const;
};

/// The fork server's argv after its program name: "--pid-fd FD" then, per child,
/// "--child ROLE LOG STDOUT_FD ARGC ARGV...". Validates `spec` first.
std::vector<std::string> encode_fork_spec(const ForkSpec& spec);

/// Inverse of encode_fork_spec(); throws InputError naming the bad item on malformed input.
ForkSpec decode_fork_spec(const std::vector<std::string>& args);

const char* fork_role_name(ForkRole role);

}  // namespace tessera::cli
