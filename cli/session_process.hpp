#pragma once
// The life of tessera-agent and tessera-coordinator around their DDS session: both print
// --help, reject bad options with exit code 2, turn SIGINT/SIGTERM into a clean stop, and on
// any failure tell the other processes why (ABORT) before leaving. Kept in one place so the
// two executables cannot drift apart in how a run ends (launch and the tests rely on the exit
// codes and the "<tag>: error: <why>" lines).

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"
#include "transport/run_failure.hpp"
#include "transport/session_options.hpp"
#include "transport/signal_watcher.hpp"

namespace tessera::cli {

/// Thrown by a process body that must leave on its own while the run goes on without it (an
/// agent refused after its block was re-partitioned): printed as "<tag>: error: <why>",
/// mapped to `exit_code`, and NO ABORT is sent to the others.
class LeaveAlone : public std::runtime_error {
 public:
  LeaveAlone(int exit_code, const std::string& why)
      : std::runtime_error(why), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

/// Who is running, for the error lines and the ABORT reasons the others receive.
struct ProcessRole {
  std::string tag;        ///< Prefix of every error line, e.g. "tessera-agent[2]".
  double timeout_s = 10;  ///< --timeout; the linger for the ABORT is min(3 s, this).
  /// On bad input, also wait the whole linger for peers not seen yet (an agent fails at
  /// start-up, typically before it has discovered everyone, and they should learn why).
  bool patient_on_bad_input = false;
  /// Agents only: once the coordinator's FINISHED has arrived (the merged result is written, the
  /// run is complete), an abort in what is left (the last steps, the others' participants
  /// leaving, the deletion of ours) ends the process with exit code 0 and a note instead of
  /// SIGABRT (Fast DDS 2.9's lease-check race, transport/fastdds/teardown_guard.hpp). An abort
  /// before FINISHED stays an abort: the run fails.
  bool cover_after_finished = false;
};

/// `usage` with its one "%s" replaced by the shared DDS session options' help.
std::string process_help(const std::string& usage);

/// The start of main(): returns 0 after printing `help` when argv (without the program name)
/// asks for --help or -h, 2 after printing "<program>: error: <why>" when `parse` throws
/// InputError, and nullopt when `out` holds the parsed options.
template <class Options, class Parse>
std::optional<int> parse_process_options(const std::vector<std::string>& argv,
                                         const std::string& program, const std::string& help,
                                         Parse parse, Options& out);

/// Opens the session of the role (exit 2 on bad session input, 1 on any other failure to open
/// it), routes the first SIGINT/SIGTERM into a stop of every wait, and runs `body`. A failure
/// in `body` is printed, relayed to the others as ABORT (their own reasons unprefixed, so
/// everyone learns the first cause) and mapped to its exit code; a stop requested while
/// failing wins over the secondary error it caused. Returns the exit code (0 when `body`
/// returned); main() then ends with transport::exit_process (transport/fastdds/process_exit.hpp).
int run_session_process(const transport::SessionOptions& options, const ProcessRole& role,
                        transport::SignalWatcher& signals,
                        const std::function<void(transport::AgentSession&)>& body);
/// The same for the coordinator (ProcessRole::cover_after_finished does not apply).
int run_session_process(const transport::SessionOptions& options, const ProcessRole& role,
                        transport::SignalWatcher& signals,
                        const std::function<void(transport::CoordinatorSession&)>& body);

// ---- implementation of the template

/// Prints "<program>: error: <why>" (the one place main() reports bad options).
void print_option_error(const std::string& program, const std::string& why);
bool asks_for_help(const std::vector<std::string>& argv);
void print_help(const std::string& help);

template <class Options, class Parse>
std::optional<int> parse_process_options(const std::vector<std::string>& argv,
                                         const std::string& program, const std::string& help,
                                         Parse parse, Options& out) {
  if (asks_for_help(argv)) {
    print_help(help);
    return transport::kExitOk;
  }
  try {
    out = parse(argv);
  } catch (const InputError& e) {
    print_option_error(program, e.what());
    return transport::kExitBadInput;
  }
  return std::nullopt;
}

}  // namespace tessera::cli
