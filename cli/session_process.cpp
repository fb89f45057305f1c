#include "session_process.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <new>
#include <tessera/util/resource_error.hpp>
#include <type_traits>

#include "session_args.hpp"
#include "transport/fastdds/teardown_guard.hpp"

namespace tessera::cli {

using namespace tessera::transport;

std::string process_help(const std::string& usage) {
  std::string help = usage;
  const std::size_t at = help.find("%s");
  if (at != std::string::npos) help.replace(at, 2, session_options_help(SessionArgsFor::kProcess));
  return help;
}

bool asks_for_help(const std::vector<std::string>& argv) {
  return std::any_of(argv.begin(), argv.end(),
                     [](const std::string& a) { return a == "--help" || a == "-h"; });
}

void print_help(const std::string& help) {
  std::fputs(help.c_str(), stdout);
}

void print_option_error(const std::string& program, const std::string& why) {
  std::cerr << program << ": error: " << why << "\n";
}

namespace {

// Prints the error and tells the other processes (ABORT), then lingers briefly so the ABORT
// reaches them before this participant disappears. `own` false: the reason came from
// another process (an ABORT received) and its origin and cause are relayed unchanged, so
// peers that never heard the original still learn the first cause and who had it instead
// of only seeing this process leave.
int leave(Session& session, const ProcessRole& role, int code, const std::string& why, bool own) {
  std::cerr << role.tag << ": error: " << why << "\n";
  try {
    const std::optional<StopInfo> stop = session.mailroom().stop_info();
    if (!own && stop && stop->origin)
      session.send_abort(stop->cause, stop->origin);
    else
      session.send_abort(why);
    const Seconds linger(std::min(3.0, role.timeout_s));
    session.linger_for_control(
        linger, code == kExitBadInput && role.patient_on_bad_input ? linger : Seconds(1.0));
  } catch (const std::exception&) {
    // Leaving anyway: the others notice this participant disappear.
  }
  return code;
}

// What a process's own failure says: a resource limit (util/resource_error.hpp, or an allocation
// refused) as "out of resources", not as the bare "std::bad_alloc".
std::string failure_text(const std::exception& e) {
  if (dynamic_cast<const ResourceError*>(&e)) return std::string("out of resources: ") + e.what();
  if (dynamic_cast<const std::bad_alloc*>(&e))
    return "out of resources: out of memory (an allocation failed)";
  return e.what();
}

// run_session_process for the session of either role: only agents read FINISHED.
template <class RoleSession>
int run_role_process(const SessionOptions& options, const ProcessRole& role, SignalWatcher& signals,
                     const std::function<void(RoleSession&)>& body) {
  // stdout may be a pipe its reader closes first (launch leaves on the first failure while the
  // coordinator still prints lag or progress lines): a failed write must not kill the process
  // (exit 141) before it has told the others and written why it stops.
  std::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<RoleSession> session;
  try {
    session = std::make_unique<RoleSession>(options);
  } catch (const InputError& e) {
    std::cerr << role.tag << ": error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << role.tag << ": error: " << e.what() << "\n";
    return kExitRunFailed;
  }
  RoleSession& s = *session;
  // After the session (destroyed first: it reads the session's flag) and around everything
  // up to the participant's deletion, whose own guard takes over inside it.
  std::optional<TeardownGuard> finished_cover;
  if constexpr (std::is_same_v<RoleSession, AgentSession>)
    if (role.cover_after_finished)
      finished_cover.emplace(kExitOk, role.tag, Seconds(0), &s.finished_flag());
  signals.start([&s](int signo) {
    s.mailroom().request_stop(exit_code_for_signal(signo), "interrupted by " + signal_name(signo));
  });
  int code = kExitOk;
  try {
    body(s);
  } catch (const LeaveAlone& e) {  // the run goes on without this process: no ABORT
    std::cerr << role.tag << ": error: " << e.what() << "\n";
    code = e.exit_code();
  } catch (const RunFailure& f) {
    code = leave(s, role, f.exit_code(), f.what(), f.tell_others());
  } catch (const InputError& e) {
    code = leave(s, role, kExitBadInput, e.what(), true);
  } catch (const std::exception& e) {
    // A stop may hide behind another error raised while stopping: prefer the cause.
    if (auto stop = s.mailroom().stop_info())
      code = leave(s, role, stop->exit_code, stop->reason, !stop->remote);
    else
      code = leave(s, role, kExitRunFailed, failure_text(e), true);
  }
  signals.stop();  // the callback refers to the session
  s.close(code);   // a Fast DDS abort or hang while deleting still exits with `code`
  return code;
}

}  // namespace

int run_session_process(const SessionOptions& options, const ProcessRole& role,
                        SignalWatcher& signals, const std::function<void(AgentSession&)>& body) {
  return run_role_process(options, role, signals, body);
}

int run_session_process(const SessionOptions& options, const ProcessRole& role,
                        SignalWatcher& signals,
                        const std::function<void(CoordinatorSession&)>& body) {
  return run_role_process(options, role, signals, body);
}

}  // namespace tessera::cli
