#include "launch/launch_loss_policy.hpp"

#include <csignal>
#include <cstdio>
#include <cstring>
#include <tessera/util/input_error.hpp>

namespace tessera::launch {

namespace {

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", s);
  return buf;
}

// "exit code 1", "killed by SIGKILL" (128 + signal is how launch records a signal death).
std::string how_it_ended(int code) {
  if (code > 128 && code < 128 + 65) {
    const char* name = sigabbrev_np(code - 128);
    if (name) return "exit code " + std::to_string(code) + ", SIG" + name;
  }
  return "exit code " + std::to_string(code);
}

}  // namespace

void LaunchLossOptions::validate() const {
  if (!(rejoin_timeout_s > 0 && rejoin_timeout_s <= 3600))
    throw InputError("launch: --rejoin-timeout must be in (0, 3600] seconds");
  if (replicas < 1 || replicas > 8) throw InputError("launch: --replicas must be 1..8");
  if (replica_every < 1) throw InputError("launch: --replica-every must be >= 1");
}

std::set<std::string> launch_loss_option_names() {
  return {"on-agent-loss", "rejoin-timeout", "replicas", "replica-every"};
}

LaunchLossOptions parse_launch_loss_options(const cli::Arguments& args) {
  LaunchLossOptions o;
  const std::string action = args.get_or("on-agent-loss", "stop");
  if (action == "continue") {
    o.action = AgentLossAction::kContinue;
  } else if (action != "stop") {
    throw InputError("launch: --on-agent-loss '" + action + "' is not one of stop, continue");
  }
  if (o.action == AgentLossAction::kStop) {
    for (const char* name : {"rejoin-timeout", "replicas", "replica-every"})
      if (args.has(name))
        throw InputError(std::string("launch: --") + name +
                         " needs --on-agent-loss continue (with stop a lost agent ends the run)");
    return o;
  }
  o.rejoin_timeout_s = args.get_double("rejoin-timeout", o.rejoin_timeout_s);
  const long replicas = args.get_long("replicas", o.replicas);
  const long every = args.get_long("replica-every", o.replica_every);
  // Range checks before the narrowing casts, so a negative value is named, not wrapped.
  if (replicas < 1 || replicas > 8) throw InputError("launch: --replicas must be 1..8");
  if (every < 1 || every > 1000000) throw InputError("launch: --replica-every must be >= 1");
  o.replicas = static_cast<unsigned>(replicas);
  o.replica_every = static_cast<unsigned>(every);
  o.validate();
  return o;
}

std::string launch_loss_help() {
  return "  --on-agent-loss A    what a dead agent process does to the run:           [stop]\n"
         "                       stop = every process stops, naming the lost agent;\n"
         "                       continue = the coordinator waits --rejoin-timeout for it,\n"
         "                       then re-partitions its block among the survivors, which\n"
         "                       finish with N-1 agents and the full estimate (needs the\n"
         "                       replicas below; one loss per run; docs/fault-tolerance.md)\n"
         "  --rejoin-timeout S   continue: seconds before a lost agent's block is\n"
         "                       re-partitioned (absorbs false alarms of the lease)   [2]\n"
         "  --replicas K         continue: neighbours holding each agent's measurements\n"
         "                       and poses, 1..8                                      [1]\n"
         "  --replica-every R    continue: rounds between pose replica updates         [10]\n";
}

std::vector<std::string> coordinator_loss_argv(const LaunchLossOptions& o) {
  if (o.action == AgentLossAction::kStop) return {};
  return {"--replicas",       std::to_string(o.replicas),
          "--replica-every",  std::to_string(o.replica_every),
          "--rejoin-timeout", seconds_text(o.rejoin_timeout_s)};
}

std::vector<std::string> agent_loss_argv(const LaunchLossOptions& o) {
  if (o.action == AgentLossAction::kStop) return {};
  return {"--udp-only"};
}

ExitVerdict judge_exit(const LaunchLossOptions& o, long agent, int code, bool coordinator_done) {
  ExitVerdict v;
  if (code == 0) return v;
  const std::string name = agent < 0 ? "coordinator" : "agent " + std::to_string(agent);
  const std::string failed = name + " failed (" + how_it_ended(code) + ")";
  // The coordinator is not replaceable, bad input is not a loss, and once the coordinator
  // has finished there is nothing left to re-partition.
  if (agent < 0 || o.action == AgentLossAction::kStop || code == 2 || code == 127 ||
      coordinator_done) {
    v.failure = failed;
    return v;
  }
  v.lost = true;
  if (code > 128) {  // died: killed or crashed
    v.notice = name + " ended during the run (" + how_it_ended(code) +
               "); continuing without it (--on-agent-loss continue): the coordinator "
               "re-partitions its block among the survivors after " +
               seconds_text(o.rejoin_timeout_s) + " s";
  } else {  // stopped on its own (an abort it received, or a failure it told the others)
    v.notice = name + " stopped (" + how_it_ended(code) +
               "); the coordinator decides whether the run goes on without it";
  }
  return v;
}

}  // namespace tessera::launch
