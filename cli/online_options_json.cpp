#include "online_options_json.hpp"

#include "run_wide_args.hpp"
#include "step_coarse_args.hpp"

namespace tessera::cli {

void add_online_solver_options(JsonObject& j, const OnlineOptions& o) {
  j.add("step_solver", o.newton_steps ? "newton" : "rounds")
      .add("step_coarse", step_coarse_name(o.newton_coarse))
      .add("step_coarse_min_blocks", o.newton_coarse_min_blocks)
      .add("step_coarse_aggregates", step_coarse_aggregates_name(o.newton_coarse_aggregates))
      .add("first_step_factors", first_step_factors_name(o.first_step_on_grown_factors))
      .add("tangent_dots", tangent_dots_name(o.solver.block_update.tangent_split_dots))
      .add("refactor_growth", o.refactor_growth)
      .add("local_rounds", o.solver.local_rounds.enabled)
      .add("local_threshold", o.solver.local_rounds.threshold);
}

JsonObject rebalance_options_json(const RebalanceOptions& b) {
  JsonObject r;
  r.add("enabled", b.enabled)
      .add("cut_fraction", b.cut_fraction)
      .add("slack", b.slack)
      .add("min_excess", b.min_excess)
      .add("max_passes", b.max_passes)
      .add("pass_patience", b.pass_patience)
      .add("place_by_links", b.place_by_links);
  return r;
}

}  // namespace tessera::cli
