#pragma once
// Solver options that change every agent's arithmetic, as `tessera solve`, `tessera launch`,
// tessera-coordinator and `tessera-agent --online` spell them: the backward dot products of
// the tangent preconditioner (--tangent-dots) and, online, the factors of a step's first Newton
// step (--first-step-factors), when a growing block's factor is rebuilt (--refactor-growth) and
// the local rounds (--no-local-rounds, --local-threshold). Over DDS every agent of a run must
// use the same value: the coordinator's assignment carries --tangent-dots
// (transport/assignment_options.hpp), and the online agents check all five against the lead's.

#include <string>
#include <tessera/online/online_engine.hpp>

#include "arguments.hpp"
#include "cli/run_wide_options.hpp"

namespace tessera::cli {

/// "split" -> true (BlockUpdateOptions::tangent_split_dots: four partial sums, the default),
/// "sequential" -> false (CHOLMOD's sequential sums, its bits); InputError naming
/// --tangent-dots otherwise.
bool parse_tangent_dots(const std::string& value);
/// The flag's value of BlockUpdateOptions::tangent_split_dots: "split" or "sequential".
const char* tangent_dots_name(bool split);
/// --tangent-dots of `args` (default split).
bool tangent_split_dots_of(const Arguments& args);

/// "grown" -> true (OnlineOptions::first_step_on_grown_factors), "new" -> false (the default);
/// InputError naming --first-step-factors otherwise.
bool parse_first_step_factors(const std::string& value);
/// The flag's value of OnlineOptions::first_step_on_grown_factors: "grown" or "new".
const char* first_step_factors_name(bool grown);
/// --first-step-factors of `args` (default new).
bool first_step_on_grown_factors_of(const Arguments& args);

/// Help text of --refactor-growth, --local-threshold and --no-local-rounds (aligned as the
/// agent's and launch's usage texts).
extern const char* const kGrowthAndLocalRoundsHelp;
/// Sets options.refactor_growth (--refactor-growth, >= 0) and options.solver.local_rounds
/// (--no-local-rounds; --local-threshold, in (0, 1]) from `args`, defaults for absent ones;
/// InputError names the bad option. `tessera solve --online`, `tessera launch --online` and
/// `tessera-agent --online` share it.
void parse_growth_and_local_rounds(const Arguments& args, OnlineOptions& options);

/// "" when an online agent's options (`mine`) equal the lead's (agent `lead_agent`; the
/// threshold only with local rounds on); else a message naming the first flag that differs,
/// both values, and why all agents must share it.
std::string run_wide_disagreement(const RunWideOptions& mine, const RunWideOptions& lead,
                                  unsigned lead_agent);

}  // namespace tessera::cli
