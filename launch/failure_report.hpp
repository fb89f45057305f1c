#pragma once
// What launch prints and returns after a failed run. When every agent fails the same way (a
// graph that cannot be split among them, a bad option value), their log tails differ only in the
// agent's own id: they are shown once, under the names of all that said it. Bad input keeps
// `tessera solve`'s exit code (2) when the failed agents all exited with it.

#include <string>
#include <vector>

namespace tessera::launch {

/// A process that ended with a failure: its name ("coordinator", "agent K"), agent id (-1 for
/// the coordinator), exit code (or 128 + signal) and the last lines of its log.
struct FailedProcess {
  std::string name;
  long agent = -1;
  int code = 0;
  std::string tail;
};

/// Failed processes whose exit code and log tail are the same but for their own agent id
/// (`tessera-agent[K]`), in the order of their first member.
struct FailureGroup {
  std::vector<const FailedProcess*> members;
  /// "coordinator", "agent 2", "agents 0, 1, 3 and 4".
  std::string label() const;
};

/// Groups `failed` (pointers into it; it must outlive the result).
std::vector<FailureGroup> group_failures(const std::vector<FailedProcess>& failed);

/// launch's exit code after a failure: 2 (bad input, as `tessera solve` returns) when some
/// agent failed and every failed agent exited with 2 (the coordinator then fails only because
/// they aborted the run), or when only the coordinator failed and exited with 2; otherwise 1.
int exit_code_after_failure(const std::vector<FailedProcess>& failed);

}  // namespace tessera::launch
