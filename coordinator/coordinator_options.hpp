#pragma once
// tessera-coordinator's command line: the options of one run (what the agents are told to
// solve, where the merged result goes, how lost agents are handled) and their parser.

#include <cstdint>
#include <string>
#include <tessera/robust/robust_options.hpp>
#include <vector>

#include "session_args.hpp"
#include "transport/session_options.hpp"

namespace tessera::coordinator {

/// Every field is an option of `tessera-coordinator --help` (defaults as documented there).
struct CoordinatorOptions {
  std::uint32_t agents = 0;     ///< --agents, 1..1000 (required).
  cli::SessionArgs net;         ///< run id, domain, lease, peers, --timeout (cli/session_args.hpp)
  double run_timeout_s = 3600;  ///< Bound on the wait for the final estimates, > 0 s.
  std::string partition = "auto";
  std::uint64_t partition_seed = 1;
  double partition_time_s = 0;  ///< --partition-time: cap of the partitioner's search, s; 0 = none.
  /// --partition-nice: the nice of the thread partitioning --graph while the agents start,
  /// relative to the process's, -20..0 (coordinator/partition_priority.hpp); 0 = the same.
  int partition_nice = 0;
  std::uint32_t rank = 0;                 ///< 0 = core's default (5).
  std::string algorithm, init;            ///< Empty algorithm = core's default (irbcd).
  std::uint32_t max_rounds = 0;           ///< 0 = core's default.
  double grad_tol = 0, rel_cost_tol = 0;  ///< 0 = core's defaults.
  std::uint64_t seed = 1;
  std::string output, tum, summary, graph_name;  ///< Empty: not written.
  std::string graph;  ///< --graph: the agents' whole g2o file, partitioned early; empty = none.
  bool progress = false, verbose = false;
  double rejoin_timeout_s = 0;   ///< 0..86400 s; 0 = a lost agent stops the run.
  double status_interval_s = 5;  ///< 0..86400 s; 0 = no status lines.
  /// Seconds between progress lines, 0..3600 (core/runtime/progress_printer.hpp; the first, the
  /// restarts and the last always print). 0 = every completed step the coordinator sees: every
  /// round while it reads the round statuses (rejoin, replicas), else one per progress digest.
  double progress_interval_s = 0.1;
  std::uint32_t replicas = 0;        ///< 0..8; 0 = no re-partition after a permanent loss.
  std::uint32_t replica_every = 10;  ///< Rounds between lifted-pose replicas, >= 1.
  bool certify = false;
  /// The agents send their round statuses through agent 0, which forwards each step's as one
  /// bundle (transport/status_relay.hpp); on by default (--status-relay, still accepted),
  /// --no-status-relay: all to all. Agents ignore it with rejoin or replicas.
  bool status_relay = true;
  /// Two-level rounds: a coarse correction every this many rounds; 0 = off (--coarse-every).
  std::uint32_t coarse_every = 0;
  /// The coarse space: 0 = one rigid motion per block (--coarse-space blocks); K > 0 = the
  /// smoothed space with K pieces per block (--coarse-space smoothed, --coarse-aggregates K)
  /// and coarse_smoothing smoothing steps (--coarse-smoothing S).
  std::uint32_t coarse_aggregates = 0;
  std::uint32_t coarse_smoothing = 1;
  /// Newton refinement after the rounds: "none", "newton" or "auto" (--refine), with its tolerances
  /// (--refine-grad-tol, --refine-rel-tol; 0 = core's defaults).
  std::string refine = "auto";
  double refine_grad_tol = 0;
  double refine_rel_tol = 0;
  /// Who factors the interface matrix of its interface solves (--refine-sigma,
  /// set_sigma_mode): "one" (agent 0, which sends its factor), "solve" (agent 0, which sends
  /// its solves), "every", or "" (core's default: solve).
  std::string refine_sigma;
  /// At most this many agents in the distributed initialisation's local solve at once
  /// (--setup-at-once; core/runtime/setup_turns.hpp): their factorizations are the set-up's
  /// memory peak, and on a few cores they share the CPU anyway. 0 = all at once.
  std::uint32_t setup_at_once = 8;
  /// BlockUpdateOptions::tangent_split_dots of every agent (--tangent-dots split|sequential).
  bool tangent_split_dots = true;
  /// Robust solve (--robust and the GNC options of cli::kRobustValued, parsed as `tessera
  /// solve` parses them; docs/robust.md).
  RobustOptions robust;
  /// GNC starts from the known inliers (off when --init is given, like `tessera solve`).
  bool gnc_known_start = true;
  /// --gnc-cluster-probes K: GncDistributedOptions::cluster_probes of every agent (0 = none).
  std::uint32_t gnc_cluster_probes = 0;
  std::string rejected;  ///< --rejected FILE: the rejected measurements, one index a line.
  /// --reference-cost F: the optimal cost f* of the graph, known from elsewhere (e.g. `tessera
  /// solve --algorithm centralized`); the summary then reports the final cost's relative gap to it,
  /// (cost - F) / F. Finite and > 0; 0 = not given (the gap is null).
  double reference_cost = 0;
};

/// The --help text; its "%s" stands for the shared session options (cli::process_help).
extern const char* const kCoordinatorUsage;

/// Parses the arguments after the program name. Throws InputError naming the bad option.
CoordinatorOptions parse_coordinator_options(const std::vector<std::string>& argv);

/// The DDS session the coordinator opens for these options.
transport::SessionOptions coordinator_session_options(const CoordinatorOptions& options);

}  // namespace tessera::coordinator
