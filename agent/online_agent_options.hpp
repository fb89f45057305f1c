#pragma once
// `tessera-agent --online`'s command line: its usage text, its options and their parser.

#include <string>
#include <tessera/online/online_engine.hpp>
#include <vector>

namespace tessera::agent {

/// Every field is an option of `tessera-agent --online --help` (defaults as documented there).
struct OnlineAgentOptions {
  int robots = 0, id = -1;
  std::string run_id;
  int domain = 0;                 ///< DDS domain, 0..232 (from the run id unless --domain).
  OnlineOptions online;           ///< Solver, certificate and growth options of every solve.
  double timeout_s = 120.0;       ///< Seconds a peer may stay silent, > 0.
  double lease_s = 2.0;           ///< DDS participant lease, seconds, 0.2..60.
  bool continue_on_loss = false;  ///< --on-agent-loss continue (else stop).
  std::string json;               ///< Summary file ("" = none).
  bool verbose = false;
  double certify_every_s = 0.0;  ///< Seconds between certificates of the growing graph (0 = off).
  double publish_every_s = 0.0;  ///< Seconds between estimate publications (0 = off).
  std::string tum_dir;           ///< Directory of the TUM snapshots ("" = none).
};

/// The text of `tessera-agent --online --help`.
const char* online_agent_usage();

/// Parses and checks argv; throws InputError naming the bad option.
OnlineAgentOptions parse_online_agent_options(const std::vector<std::string>& argv);

}  // namespace tessera::agent
