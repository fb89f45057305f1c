#pragma once
// Launch flags that are passed on unchanged to the coordinator and/or the agents. Adding such a
// flag is one row in forwarded_flags.cpp: launch then accepts it, lists it in --help, checks its
// value and appends it to the right processes' argv (launch_argv.hpp).

#include <string>
#include <vector>

namespace tessera::launch {

/// Which processes of the run receive a forwarded flag.
enum class ForwardTo { kCoordinator, kAgents, kBoth };

struct ForwardedFlag {
  const char* name;    ///< launch's flag, without "--"
  const char* target;  ///< the flag the processes receive, without "--" (often `name`)
  bool valued;         ///< takes a value (else a switch)
  ForwardTo to;
  const char* usage;  ///< --help's left column, e.g. "--out FILE"
  const char* help;   ///< --help's text; more lines are indented to the text column
  /// Throws InputError naming the flag when `value` is not valid; null: the receiving process
  /// checks it.
  void (*check)(const std::string& value);
};

/// Every forwarded flag, in the order they are appended to the argv and listed in --help.
const std::vector<ForwardedFlag>& forwarded_flags();

/// The row named `name` (without "--"), or null.
const ForwardedFlag* find_forwarded_flag(const std::string& name);

/// --help lines of the forwarded flags (two-space indent, as the rest of launch's help).
std::string forwarded_flags_help();

}  // namespace tessera::launch
