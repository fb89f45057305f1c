#pragma once
// Public API: a whole distributed run on this host as separate processes, the coordinator and
// N agents (the tessera-coordinator and tessera-agent executables) talking over DDS; what
// `tessera launch` runs. Prints the coordinator's progress and the summary on stdout.

#include <string>
#include <tessera/dds/session.hpp>
#include <vector>

namespace tessera::dds {

struct LaunchOptions {
  /// A g2o file, a folder of robot files or a comma-separated list; "" = a generated grid.
  std::string graph;
  long agents = 3;                  ///< 1..64
  std::string algorithm = "irbcd";  ///< rbcd | rbcd++ | irbcd
  std::string partition = "auto";   ///< auto | sequential | fast | eco | strong | highest
  double grad_tol = 0.01;           ///< > 0
  bool certify = true;
  std::string json;        ///< Also write the summary here ("" = not).
  std::string out;         ///< Merged poses (g2o); "" = not written.
  double timeout_s = 600;  ///< Time limit of the whole run, > 0 s.
  bool quiet = false;      ///< No progress lines.
  /// The session options of every process (its timeout_s is not used: see timeout_s).
  SessionOptions session;
  /// Folder of tessera-coordinator and tessera-agent. "" = the first folder that holds both of:
  /// the running program's folder (a build tree, or a program installed beside them); the
  /// bindir of the install prefix the library was configured with; the folders on PATH. A
  /// package installed into another prefix (`cmake --install --prefix P`) is found through
  /// PATH or through this field: after find_package(Tessera), `Tessera_BINDIR` is P's bindir,
  /// e.g. `target_compile_definitions(app PRIVATE TESSERA_BINDIR="${Tessera_BINDIR}")`.
  std::string bin_dir;
  /// More `tessera launch` options, as on its command line (tessera launch --help).
  std::vector<std::string> extra_args;

  /// `tessera launch`'s command line for these options (without "launch").
  std::vector<std::string> argv() const;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct LaunchResult {
  /// 0 done, 1 the run failed (a process failed, or the time limit), 130 interrupted.
  int exit_code = 0;
  std::string run_id;
  std::string failure;       ///< Why the run failed ("" when exit_code is 0).
  std::string summary_json;  ///< The coordinator's JSON summary ("" when none was written).
  /// Processes lost during the run that the run went on without ("agent 2").
  std::vector<std::string> lost;
  /// Notes of the processes' logs (e.g. a Fast DDS abort covered at the end of the run).
  std::vector<std::string> notes;
  double wall_s = 0;  ///< Seconds from the processes' start to the end of the run.

  /// A few lines for people: outcome, run id, wall time, losses and notes, the summary.
  std::string full_report() const;
};

/// Runs the whole run (validate() first: InputError on bad options; std::runtime_error when
/// the processes cannot be started).
LaunchResult launch(const LaunchOptions& options);

}  // namespace tessera::dds
