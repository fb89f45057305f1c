#pragma once
// tessera-agent's command line: which robot's data this process brings, where it writes,
// its checkpoints, and their parser.

#include <cstdint>
#include <string>
#include <vector>

#include "session_args.hpp"
#include "transport/session_options.hpp"

namespace tessera::agent {

/// Every field is an option of `tessera-agent --help` (defaults as documented there).
struct AgentOptions {
  std::string graph;         ///< --graph: the whole multi-robot g2o file or this robot's own file.
  std::uint32_t robots = 0;  ///< --robots N, 1..1000 (= agents of the run).
  std::uint32_t id = 0;      ///< --id, 0..N-1.
  cli::SessionArgs net;      ///< run id, domain, lease, peers, --timeout (cli/session_args.hpp)
  double round_timeout_s = 600;  ///< Bound on each wait for a peer during the rounds, > 0 s.
  std::string output;            ///< Empty: not written.
  std::string dump_local;        ///< Empty: not written.
  std::string checkpoint_dir;    ///< Empty: no checkpoints (and no rejoin).
  int checkpoint_every = 1;      ///< Rounds between checkpoints, >= 1.
  bool udp_only = false;         ///< No shared memory (implied by checkpoint_dir).
  /// --handshake-stall S: with --security, a peer discovered but not authenticated for this
  /// long before the agent announces itself makes it re-create its participant
  /// (transport/peer_gate.hpp), > 0 s.
  double handshake_stall_s = 4;
  int handshake_retries = 3;  ///< --handshake-retries: at most this many re-creations, 0..10.
  /// --handshake-force-once (a test hook): re-create once at the first unfinished handshake,
  /// outside the handshake_retries budget (PeerGateOptions::force_one_reopen).
  bool handshake_force_once = false;
  /// --early-chordal: agent 0 starts the whole graph's chordal initialization as soon as it has
  /// the preloaded file (runtime/early_chordal.hpp).
  bool early_chordal = false;
  bool verbose = false;
};

/// The --help text; its "%s" stands for the shared session options (cli::process_help).
extern const char* const kAgentUsage;

/// Parses the arguments after the program name. Throws InputError naming the bad option.
AgentOptions parse_agent_options(const std::vector<std::string>& argv);

/// The DDS session the agent opens for these options.
transport::SessionOptions agent_session_options(const AgentOptions& options);

}  // namespace tessera::agent
