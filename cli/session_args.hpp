#pragma once
// The DDS session options shared by tessera-agent and tessera-coordinator and forwarded by
// `tessera launch`, parsed in ONE place: a session option is added here once and every
// process of a run accepts it, documents it in --help and passes it on the same way.
// No Fast DDS types: `tessera` itself does not link Fast DDS.

#include <set>
#include <string>
#include <vector>

#include "arguments.hpp"
#include "transport/session_options.hpp"

namespace tessera::cli {

/// Who parses the options: a run process (agent, coordinator) also takes --timeout, the
/// bound on each set-up wait; `tessera launch` has its own --timeout (the whole run).
enum class SessionArgsFor { kProcess, kLaunch };

/// The shared session options of one process.
struct SessionArgs {
  /// --run-id, --domain, --lease, --peers, --network, --security (role fields left at their
  /// defaults: the caller sets coordinator / agent_id / num_agents / verbose).
  transport::SessionOptions session;
  /// --timeout S (kProcess only): bound on each wait for peers during set-up and shutdown,
  /// seconds, > 0. Default 30.
  double timeout_s = 30;
};

/// Names (without "--") of the valued options parse_session_args reads, to add to the
/// caller's cli::Arguments list.
std::set<std::string> session_option_names(SessionArgsFor who);

/// Adds session_option_names(who) to `names` (convenience for building an Arguments list).
std::set<std::string> with_session_options(std::set<std::string> names, SessionArgsFor who);

/// Reads the shared options (defaults above / in SessionOptions) and checks them; throws
/// InputError naming the option ("option --domain: must be 0..232").
SessionArgs parse_session_args(const Arguments& args, SessionArgsFor who);

/// The command-line arguments that make a tessera-agent / tessera-coordinator join the run
/// described by `o`: --run-id always, the others only when they differ from the defaults.
/// parse_session_args(session_argv(o)) gives back o's run id, domain, lease, peers, network and
/// security folder.
std::vector<std::string> session_argv(const transport::SessionOptions& o);

/// --help lines describing the shared options (two-space indent, one option per entry).
std::string session_options_help(SessionArgsFor who);

}  // namespace tessera::cli
