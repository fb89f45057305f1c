#pragma once
// Public API: run the coordinator of a distributed run over DDS inside your own program.
// run_coordinator() is what the tessera-coordinator executable runs: it waits for the agents,
// partitions the structure they announce, publishes the assignment, follows the rounds and
// gathers and writes the merged estimate.

#include <cstdint>
#include <string>
#include <tessera/dds/session.hpp>
#include <vector>

namespace tessera::dds {

struct CoordinatorOptions {
  std::uint32_t agents = 0;  ///< Agents of the run, 1..1000 (required).
  SessionOptions session;
  std::string partition = "auto";   ///< auto | sequential | fast | eco | strong | highest
  std::string algorithm = "irbcd";  ///< rbcd | rbcd++ | irbcd
  double grad_tol = 0;              ///< Stop at this gradient norm; 0 = the solver's default.
  std::uint32_t max_rounds = 0;     ///< 0 = the solver's default.
  bool certify = false;             ///< Certify global optimality after the solve.
  std::string output;               ///< Merged poses (g2o); "" = not written.
  std::string summary;              ///< JSON summary file; "" = a temporary one.
  double run_timeout_s = 3600;      ///< Bound on the wait for the final estimates, > 0 s.
  bool progress = false;            ///< Progress lines on stdout.
  /// More tessera-coordinator options, as on its command line (tessera-coordinator --help).
  std::vector<std::string> extra_args;

  /// tessera-coordinator's command line for these options (without the program name).
  std::vector<std::string> argv() const;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct RunSummary {
  /// 0 done; 1 the run failed; 2 bad input; 130 interrupted (tessera-coordinator's codes).
  int exit_code = 0;
  std::string run_id;
  /// The run's JSON summary as the coordinator wrote it (rounds, cost, certificate, timing,
  /// faults); "" when the run ended before it.
  std::string summary_json;
  double wall_s = 0;  ///< Seconds spent in run_coordinator().

  /// A few lines for people, then the JSON summary.
  std::string full_report() const;
};

/// Runs the coordinator to the end of the run (validate() first: InputError on bad options).
RunSummary run_coordinator(const CoordinatorOptions& options);

}  // namespace tessera::dds
