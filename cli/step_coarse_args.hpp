#pragma once
// The coarse correction of an online run's Newton steps (OnlineOptions::newton_coarse,
// newton_coarse_min_blocks and newton_coarse_aggregates, docs/online.md) as `tessera solve
// --online`, `tessera launch
// --online` and `tessera-agent --online` spell it, and the agreement the DDS agents check: the
// correction adds message steps to every CG iteration of every agent, so all must use the
// same options (the lead's).

#include <string>
#include <tessera/online/online_engine.hpp>

#include "arguments.hpp"

namespace tessera::cli {

/// Valued option names (without "--"), null-terminated: step-coarse, step-coarse-min-blocks,
/// step-coarse-aggregates.
extern const char* const kStepCoarseValued[];
/// Help text of those options (aligned as the agent's and launch's usage texts).
extern const char* const kStepCoarseHelp;

/// "none", "blocks" or "smoothed": the flag's value for `c`.
const char* step_coarse_name(NewtonRefineOptions::Coarse c);

/// The coarse correction `value` names ("none", "blocks" or "smoothed"); InputError names
/// `flag` (e.g. "--refine-coarse") otherwise. Batch and online flags share it.
NewtonRefineOptions::Coarse coarse_from_flag(const std::string& flag, const std::string& value);

/// Sets options.newton_coarse, newton_coarse_min_blocks and newton_coarse_aggregates from the
/// flags (their defaults for
/// absent ones); InputError names the bad option.
void parse_step_coarse_options(const Arguments& args, OnlineOptions& options);

/// "auto" for OnlineOptions::kCoarseAggregatesAuto, else the number: the flag's value.
std::string step_coarse_aggregates_name(int aggregates);

/// "" when `mine` equals `lead` (coarse correction and, with one, its minimum group; with the
/// smoothed one, its pieces per block); otherwise a message naming the first option that
/// differs with both values, e.g. "option --step-coarse: this agent's none differs from the
/// lead's (agent 0) smoothed ...".
std::string step_coarse_disagreement(NewtonRefineOptions::Coarse mine, int mine_min_blocks,
                                     int mine_aggregates, NewtonRefineOptions::Coarse lead,
                                     int lead_min_blocks, int lead_aggregates, unsigned lead_agent);

}  // namespace tessera::cli
