#pragma once
// The re-partition options of an online run (RebalanceOptions, docs/online.md "The partition
// follows the graph") as `tessera solve --online`, `tessera launch --online` and
// `tessera-agent --online` spell them, and the agreement the DDS agents check: every agent
// holds the whole graph and moves the blocks itself, without a message, so all must use the
// same options (the lead's).

#include <string>
#include <tessera/online/block_rebalance.hpp>

#include "arguments.hpp"

namespace tessera::cli {

/// Valued option names (without "--"), null-terminated: cut-fraction, block-slack,
/// block-min-excess, cut-passes, cut-patience.
extern const char* const kRebalanceValued[];
/// Switches (without "--"), null-terminated: no-place-by-links, no-rebalance.
extern const char* const kRebalanceSwitches[];
/// Help text of those options (one line each, aligned as the commands' usage texts).
extern const char* const kRebalanceHelp;

/// The options as given (defaults for absent ones), validated: InputError names the option.
RebalanceOptions parse_rebalance_options(const Arguments& args);

/// "" when `mine` equals `lead` field by field; otherwise a message naming the first option
/// that differs with both values, e.g. "option --cut-fraction: this agent's 0.05 differs from
/// the lead's (agent 0) 0.02 ...".
std::string rebalance_disagreement(const RebalanceOptions& mine, const RebalanceOptions& lead,
                                   unsigned lead_agent);

}  // namespace tessera::cli
