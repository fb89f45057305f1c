#pragma once
// The online solver's options as the JSON summaries of `tessera solve --online` and of every
// `tessera-agent --online` report them: one writer, so the two spell each field alike.

#include <tessera/online/online_engine.hpp>

#include "json_writer.hpp"

namespace tessera::cli {

/// Adds step_solver, step_coarse, step_coarse_min_blocks, step_coarse_aggregates,
/// first_step_factors, tangent_dots, refactor_growth, local_rounds and local_threshold (the
/// flags' spellings where a flag names the value) to `j`.
void add_online_solver_options(JsonObject& j, const OnlineOptions& options);

/// The rebalancing thresholds (OnlineOptions::rebalance) as one object.
JsonObject rebalance_options_json(const RebalanceOptions& rebalance);

}  // namespace tessera::cli
