#include "agent/agent_options.hpp"

#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "runtime/checkpoint_keeper.hpp"

namespace tessera::agent {

// %s: the shared DDS session options (cli/session_args.hpp).
const char* const kAgentUsage = R"(usage: tessera-agent --graph FILE --robots N --id I [options]

One agent (robot) of a distributed Tessera run. Reads robot I's share of a multi-robot
g2o file (its contiguous poses [I n/N, (I+1) n/N) and the measurements starting there),
announces its graph structure to the coordinator, hands measurements and initial poses
to the agents that own them after the partition (peer to peer: the coordinator never sees
measurement values), runs the round protocol and sends its final poses to the coordinator.

options:
  --graph FILE       g2o file of the whole multi-robot graph (required), or a file with only
                     this robot's data (it starts with '# tessera-robot poses BEGIN END';
                     written by tessera generate --split; see docs/dds-runtime.md)
  --robots N         number of robots = agents of the run (required)
  --id I             this agent's id, 0..N-1 (required)
  --round-timeout S  bound on each wait for a peer's message during the rounds (default 600)
  --output FILE      write this agent's final poses as g2o VERTEX lines
  --dump-local FILE  write the local problem after the hand-off (text; see docs/dds-runtime.md)
  --checkpoint-dir DIR  keep this agent's checkpoint in DIR (one folder per run). Started
                     again with the same options after a crash, the agent finds it there and
                     rejoins the run (the coordinator needs --rejoin-timeout); removed when
                     the run completes. A damaged checkpoint is an error naming the file.
  --checkpoint-every K  write the checkpoint every K rounds (default 1)
  --udp-only         talk UDP only, no shared memory (implied by --checkpoint-dir): for runs
                     that survive a SIGKILLed peer (tessera launch --on-agent-loss continue)
  --handshake-stall S  with --security: a peer still unauthenticated S seconds after it was
                     discovered (a stalled Fast DDS 2.9 handshake) makes this agent re-create
                     its participant before it announces itself (default 4)
  --handshake-retries K  at most K such re-creations, 0..10 (default 3)
  --handshake-force-once  (a test hook) with --security: re-create the participant once at
                     the first handshake not finished yet, without using up a retry
  --early-chordal    agent 0, whole file parsed by tessera launch's fork server: solve the
                     whole graph's chordal initialization while the processes discover each
                     other; used only if the run's --init is chordal and the values the agents
                     send are that file's (tessera launch passes it with --init chordal)
  --verbose          print each phase
  --help             this text

DDS session options (shared with tessera-coordinator and tessera launch):
%s
exit codes: 0 done, 1 the run failed (lost peer, abort, timeout), 2 bad options or input,
128+signal when interrupted (SIGINT 130, SIGTERM 143).
)";

AgentOptions parse_agent_options(const std::vector<std::string>& argv) {
  cli::Arguments args(argv,
                      cli::with_session_options({"graph", "robots", "id", "round-timeout", "output",
                                                 "dump-local", "checkpoint-dir", "checkpoint-every",
                                                 "handshake-stall", "handshake-retries"},
                                                cli::SessionArgsFor::kProcess),
                      {"verbose", "help", "udp-only", "handshake-force-once", "early-chordal"});
  if (!args.positional().empty())
    throw InputError("unexpected argument '" + args.positional().front() + "' (see --help)");
  AgentOptions a;
  if (!args.has("graph")) throw InputError("option --graph is required (see --help)");
  if (!args.has("robots")) throw InputError("option --robots is required (see --help)");
  if (!args.has("id")) throw InputError("option --id is required (see --help)");
  a.graph = *args.get("graph");
  long robots = args.get_long("robots", 0), id = args.get_long("id", 0);
  if (robots < 1 || robots > 1000) throw InputError("option --robots: must be 1..1000");
  if (id < 0 || id >= robots)
    throw InputError("option --id: must be 0.." + std::to_string(robots - 1));
  a.robots = static_cast<std::uint32_t>(robots);
  a.id = static_cast<std::uint32_t>(id);
  a.net = cli::parse_session_args(args, cli::SessionArgsFor::kProcess);
  a.round_timeout_s = args.get_double("round-timeout", a.round_timeout_s);
  if (!(a.round_timeout_s > 0)) throw InputError("option --round-timeout: must be positive");
  a.output = args.get_or("output", "");
  a.dump_local = args.get_or("dump-local", "");
  a.checkpoint_dir = args.get_or("checkpoint-dir", "");
  a.udp_only = args.has("udp-only");
  a.checkpoint_every = static_cast<int>(args.get_long("checkpoint-every", 1));
  CheckpointOptions{a.checkpoint_dir, a.checkpoint_every}.validate();
  a.handshake_stall_s = args.get_double("handshake-stall", a.handshake_stall_s);
  if (!(a.handshake_stall_s > 0) || a.handshake_stall_s > 3600)
    throw InputError("option --handshake-stall: must be in (0, 3600] seconds");
  const long retries = args.get_long("handshake-retries", a.handshake_retries);
  if (retries < 0 || retries > 10) throw InputError("option --handshake-retries: must be 0..10");
  a.handshake_retries = static_cast<int>(retries);
  a.handshake_force_once = args.has("handshake-force-once");
  a.early_chordal = args.has("early-chordal");
  a.verbose = args.has("verbose");
  return a;
}

transport::SessionOptions agent_session_options(const AgentOptions& options) {
  transport::SessionOptions so = options.net.session;
  // An agent meant to survive a SIGKILL talks UDP only (see transport/qos.hpp).
  so.shared_memory = options.checkpoint_dir.empty() && !options.udp_only;
  so.coordinator = false;
  so.agent_id = options.id;
  so.num_agents = options.robots;
  so.verbose = options.verbose;
  return so;
}

}  // namespace tessera::agent
