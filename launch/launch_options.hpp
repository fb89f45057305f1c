#pragma once
// What `tessera launch` (and launch() in a program) is asked to run: one distributed solve on
// this host as separate processes, the coordinator and N agents talking over DDS.

#include <string>
#include <utility>
#include <vector>

#include "cli/session_args.hpp"
#include "launch/launch_loss_policy.hpp"

namespace tessera::launch {

struct LaunchOptions {
  /// One g2o file (robot k reads its sequential share), a folder of robot files or a
  /// comma-separated list of them (robot k reads the k-th), or "" to generate a grid3d graph of
  /// `poses` poses into the run's temporary folder.
  std::string graph;
  /// Agent processes, 1..64; with robot files, exactly one per file.
  long agents = 3;
  /// rbcd | rbcd++ | irbcd.
  std::string algorithm = "irbcd";
  /// Partition preset of the coordinator: auto | sequential | fast | eco | strong | highest.
  std::string partition = "auto";
  /// chordal | distributed | file.
  std::string init = "chordal";
  /// --init was given: a robust run then starts from it instead of the known inliers.
  bool init_given = false;
  /// Stop when the gradient norm is at most this (> 0).
  double grad_tol = 0.01;
  /// Round limit, >= 0 (0 = the solver's default).
  long max_rounds = 0;
  /// Relaxation rank, >= 0 (0 = the solver's default).
  long rank = 0;
  /// Solver and partition seed, >= 0.
  long seed = 1;
  /// The agents certify global optimality after the solve (and escape saddles).
  bool certify = true;
  /// Also write the coordinator's JSON summary here ("" = only into the temporary folder).
  std::string json;
  /// Keep the processes' logs (and the summary, a generated graph) in this folder, created when
  /// missing ("" = a temporary folder removed at the end).
  std::string keep_logs;
  /// Time limit of the whole run, seconds, > 0.
  double timeout_s = 600;
  /// Poses of the generated graph (graph == ""), >= agents.
  long poses = 1000;
  /// No progress lines on stdout.
  bool quiet = false;
  /// What a dead agent does to the run (--on-agent-loss and its options).
  LaunchLossOptions loss;
  /// The DDS session options passed to every process. An empty run id gets a fresh one.
  cli::SessionArgs net;
  /// launch picks the transport (launch_transport.hpp) unless --transport was given.
  bool choose_transport = true;
  /// --lease was not given: launch chooses it for the team's size (launch_lease_s).
  bool choose_lease = true;
  /// Flags passed on as they are (forwarded_flags.hpp): (name without "--", value; "" for a
  /// switch), in any order.
  std::vector<std::pair<std::string, std::string>> forwarded;

  // Advanced: how the processes start and talk (defaults measured best; docs/dds-runtime.md).
  /// Start the processes through tessera-fork-server (Fast DDS loaded once) instead of exec.
  bool fork_server = true;
  /// The agents start in SCHED_BATCH until their assignment (launch/startup_batch.hpp).
  bool agents_batch = true;
  /// Round statuses relayed through agent 0 instead of all to all.
  bool status_relay = true;
  /// Folder of tessera-coordinator, tessera-agent and tessera-fork-server; "" = the running
  /// program's own.
  std::string bin_dir;

  /// The robot files named by `graph` (empty for one whole file or a generated graph).
  std::vector<std::string> robot_files() const;

  /// Throws InputError naming the first bad field ("launch: --agents must be in 1..64").
  void validate() const;
};

/// `tessera launch`'s command line (without "launch") as options; validated. Throws InputError
/// naming the bad option.
LaunchOptions parse_launch_options(const std::vector<std::string>& argv);

/// Whether `argv` asks for --help.
bool wants_launch_help(const std::vector<std::string>& argv);

/// `tessera launch --help`.
std::string launch_help();

}  // namespace tessera::launch
