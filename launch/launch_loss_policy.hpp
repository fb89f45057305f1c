#pragma once
// What `tessera launch` does when one of its agent processes dies during a run.
//
// `stop` (the default) keeps the behaviour operators and tests rely on: the first agent that
// fails takes the whole run down, with a message naming it. `continue` hands the decision to
// the coordinator's loss path (docs/fault-tolerance.md, "An agent is lost for good"): the
// coordinator waits `--rejoin-timeout` for the agent, then re-partitions its block among the
// survivors, which take over its measurements from the replicas and finish with N - 1
// agents. The launcher only stops tolerating when the coordinator itself fails (it alone
// knows whether a loss is covered: a second loss, or an agent lost before the replicas
// existed, make it stop with its own message).
//
// No Fast DDS here: `tessera` itself does not link it.

#include <set>
#include <string>
#include <vector>

#include "cli/arguments.hpp"

namespace tessera::launch {

enum class AgentLossAction {
  kStop,      ///< a dead agent stops every process (exit 1, naming the agent)
  kContinue,  ///< a dead agent is left to the coordinator: re-partition for the survivors
};

/// The launch options of the loss path. Defaults are what `tessera launch --help` prints.
struct LaunchLossOptions {
  /// --on-agent-loss stop|continue. Default stop.
  AgentLossAction action = AgentLossAction::kStop;
  /// --rejoin-timeout S (continue only): seconds the coordinator waits for a lost agent
  /// before re-partitioning its block. launch never restarts an agent, so this window only
  /// absorbs false alarms (a live peer dropped by the DDS lease on a busy host comes back
  /// within it). (0, 3600], default 2.
  double rejoin_timeout_s = 2;
  /// --replicas K (continue only): neighbours holding each agent's measurements and lifted
  /// poses, 1..8. Default 1 (covers one lost agent).
  unsigned replicas = 1;
  /// --replica-every R (continue only): rounds between two replica updates of the lifted
  /// poses, >= 1. Default 10. Staleness costs rounds, not accuracy.
  unsigned replica_every = 10;

  /// Throws InputError naming the bad field ("launch: --replicas must be 1..8").
  void validate() const;
};

/// Valued option names (without "--") read by parse_launch_loss_options.
std::set<std::string> launch_loss_option_names();

/// Reads and validates the options above. --rejoin-timeout, --replicas and --replica-every
/// given without `--on-agent-loss continue` are an InputError (they would have no effect).
LaunchLossOptions parse_launch_loss_options(const cli::Arguments& args);

/// --help lines for the options above (two-space indent, as the rest of launch's help).
std::string launch_loss_help();

/// Extra tessera-coordinator arguments (empty for stop).
std::vector<std::string> coordinator_loss_argv(const LaunchLossOptions& o);

/// Extra tessera-agent arguments (empty for stop). With continue the agents talk UDP only:
/// a peer SIGKILLed while writing into a shared-memory port can leave that port unusable
/// for the survivors (see transport/qos.hpp).
std::vector<std::string> agent_loss_argv(const LaunchLossOptions& o);

/// How launch reads the end of one of its processes.
struct ExitVerdict {
  /// Non-empty: the run failed; this is the reason launch prints ("agent 1 failed (exit code
  /// 137)"). Empty: keep running.
  std::string failure;
  /// Non-empty: an agent ended and the run goes on (for now) without it; launch prints this
  /// once.
  std::string notice;
  /// True when the process counts as lost (its death was tolerated).
  bool lost = false;
};

/// Judges one ended process. `agent` is the agent id, or -1 for the coordinator; `code` the
/// exit code or 128 + signal; `coordinator_done` whether the coordinator has already exited 0
/// (the estimate is complete and written; an agent failing after that is a failure, not a
/// loss). Bad input (exit 2) or an agent that could not start (127) always stops the run.
ExitVerdict judge_exit(const LaunchLossOptions& o, long agent, int code, bool coordinator_done);

}  // namespace tessera::launch
