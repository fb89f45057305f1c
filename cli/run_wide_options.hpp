#pragma once
// The solver options every online agent of a DDS run must share with the lead
// (cli/run_wide_args.hpp checks them): what the agents' reports carry of OnlineOptions.

#include <tessera/online/online_engine.hpp>

namespace tessera::cli {

struct RunWideOptions {
  bool first_step_on_grown_factors = false;  ///< first_step_on_grown_factors
  bool tangent_split_dots = true;            ///< solver.block_update.tangent_split_dots
  bool local_rounds = true;                  ///< solver.local_rounds.enabled
  double local_threshold = 1.0;              ///< solver.local_rounds.threshold
  double refactor_growth = 0.0;              ///< refactor_growth
};

/// The fields above of `o`.
inline RunWideOptions run_wide_options_of(const OnlineOptions& o) {
  RunWideOptions r;
  r.first_step_on_grown_factors = o.first_step_on_grown_factors;
  r.tangent_split_dots = o.solver.block_update.tangent_split_dots;
  r.local_rounds = o.solver.local_rounds.enabled;
  r.local_threshold = o.solver.local_rounds.threshold;
  r.refactor_growth = o.refactor_growth;
  return r;
}

}  // namespace tessera::cli
