#pragma once
// Public API: host one agent of a distributed run over DDS inside your own program.
// run_agent() is what the tessera-agent executable runs: it joins the run named by
// `session`, announces its share of the graph, waits for the coordinator's assignment, runs
// the rounds with its peers and returns when the coordinator has the merged estimate.
//
//   tessera::dds::AgentOptions o;
//   o.graph = "robot0.g2o"; o.robots = 3; o.id = 0; o.session.run_id = "demo";
//   const tessera::dds::AgentResult r = tessera::dds::run_agent(o);
//
// While it runs, SIGINT and SIGTERM of the process stop the agent cleanly (they are blocked in
// the calling thread and handled by a thread of the agent), as in tessera-agent.

#include <cstdint>
#include <string>
#include <tessera/dds/session.hpp>
#include <vector>

namespace tessera::dds {

struct AgentOptions {
  /// The whole multi-robot g2o file (the agent takes its sequential share) or this robot's
  /// own file (tessera generate --split).
  std::string graph;
  std::uint32_t robots = 0;  ///< Agents of the run, 1..1000.
  std::uint32_t id = 0;      ///< This agent, 0..robots-1.
  SessionOptions session;
  double round_timeout_s = 600;  ///< Bound on each wait for a peer during the rounds, > 0 s.
  std::string output;            ///< This agent's final poses (g2o); "" = not written.
  std::string checkpoint_dir;    ///< Checkpoints (and rejoin after a restart); "" = none.
  int checkpoint_every = 1;      ///< Rounds between checkpoints, >= 1.
  bool verbose = false;          ///< Progress of the run's steps on stderr.
  /// More tessera-agent options, as on its command line (tessera-agent --help).
  std::vector<std::string> extra_args;

  /// tessera-agent's command line for these options (without the program name).
  std::vector<std::string> argv() const;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct AgentResult {
  /// 0 done; 1 the run failed; 2 bad input; 130 interrupted (as tessera-agent's exit codes).
  int exit_code = 0;
  std::uint32_t id = 0;
  std::string run_id;
  std::string output;  ///< The file written with this agent's poses ("" when none).
  double wall_s = 0;   ///< Seconds spent in run_agent().

  /// A few lines for people: agent, run, outcome, wall time, output.
  std::string full_report() const;
};

/// Runs one agent to the end of the run (validate() first: InputError on bad options). Errors
/// of the run are printed on stderr ("tessera-agent[K]: error: ...") and give a non-zero
/// exit_code.
AgentResult run_agent(const AgentOptions& options);

}  // namespace tessera::dds
