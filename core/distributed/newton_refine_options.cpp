// NewtonRefineOptions: validation, the --refine mode parser and the coarse space's options;
// the refinement's state machine is newton_refine.cpp.
#include <string>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void NewtonRefineOptions::validate() const {
  auto fail = [](const char* field, const char* why) {
    throw InputError(std::string("NewtonRefineOptions.") + field + " " + why);
  };
  if (!(grad_norm_tol > 0)) fail("grad_norm_tol", "must be > 0");
  if (!(relative_decrease_tol >= 0)) fail("relative_decrease_tol", "must be >= 0");
  if (max_steps <= 0) fail("max_steps", "must be > 0");
  if (max_cg_iterations <= 0) fail("max_cg_iterations", "must be > 0");
  if (!(forcing > 0 && forcing < 1)) fail("forcing", "must be in (0, 1)");
  if (!(forcing_power >= 0)) fail("forcing_power", "must be >= 0");
  if (!(initial_radius >= 0)) fail("initial_radius", "must be >= 0");
  if (!(accept_ratio >= 0 && accept_ratio < 0.25)) fail("accept_ratio", "must be in [0, 0.25)");
  if (max_backtracks < 0) fail("max_backtracks", "must be >= 0");
  if (coarse_aggregates < 1) fail("coarse_aggregates", "must be >= 1");
  if (coarse_poses_per_aggregate < 0) fail("coarse_poses_per_aggregate", "must be >= 0");
  if (coarse_smoothing_steps < 0 || coarse_smoothing_steps > 8)
    fail("coarse_smoothing_steps", "must be in 0..8");
  if (coarse_min_blocks < 2) fail("coarse_min_blocks", "must be >= 2");
  if (coarse_keep_steps < 1) fail("coarse_keep_steps", "must be >= 1");
  if (!(auto_gap_tol > 0)) fail("auto_gap_tol", "must be > 0");
  if (auto_window < 1) fail("auto_window", "must be >= 1");
  if (translation_iterations < 0) fail("translation_iterations", "must be >= 0");
  if (!(translation_tol > 0 && translation_tol < 1)) fail("translation_tol", "must be in (0, 1)");
  if (translation_interface_max_poses < 0) fail("translation_interface_max_poses", "must be >= 0");
  if (translation_one_factor_min_poses < 0)
    fail("translation_one_factor_min_poses", "must be >= 0");
  if (interface_max_coordinates < 0) fail("interface_max_coordinates", "must be >= 0");
  if (!(auto_interface_grad_tol >= 0)) fail("auto_interface_grad_tol", "must be >= 0");
  if (!(interface_shift > 0 && interface_shift <= 1e-3))
    fail("interface_shift", "must be in (0, 1e-3]");
  if (sigma_factoring != SigmaFactoring::kEveryAgent &&
      sigma_factoring != SigmaFactoring::kShipFactor &&
      sigma_factoring != SigmaFactoring::kShipSolves)
    fail("sigma_factoring", "must be kEveryAgent, kShipFactor or kShipSolves");
  if (ship_solves_min_coordinates < 0) fail("ship_solves_min_coordinates", "must be >= 0");
}

void set_refine_mode(NewtonRefineOptions& options, const std::string& mode) {
  if (mode != "newton" && mode != "auto" && mode != "none")
    throw InputError("option --refine: '" + mode + "' is not one of newton, auto, none");
  options.enabled = mode != "none";
  options.when = mode == "auto" ? NewtonRefineOptions::When::kIfRoundsSlow
                                : NewtonRefineOptions::When::kAlways;
}

void set_sigma_mode(NewtonRefineOptions& options, const std::string& mode,
                    const std::string& what) {
  if (mode != "every" && mode != "one" && mode != "solve")
    throw InputError(what + ": '" + mode + "' is not one of every, one, solve");
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  options.sigma_factoring = mode == "every" ? SigmaFactoring::kEveryAgent
                            : mode == "one" ? SigmaFactoring::kShipFactor
                                            : SigmaFactoring::kShipSolves;
}

std::string sigma_mode(const NewtonRefineOptions& options) {
  switch (options.sigma_factoring) {
    case NewtonRefineOptions::SigmaFactoring::kEveryAgent:
      return "every";
    case NewtonRefineOptions::SigmaFactoring::kShipFactor:
      return "one";
    case NewtonRefineOptions::SigmaFactoring::kShipSolves:
      return "solve";
  }
  return "solve";  // not reached: validate() rejects other values
}

CoarseOptions NewtonRefineOptions::coarse_space_options() const {
  CoarseOptions c;
  c.space = CoarseSpaceKind::kSmoothed;
  c.aggregates = coarse_aggregates;
  c.poses_per_aggregate = coarse_poses_per_aggregate;
  c.smoothing_steps = coarse_smoothing_steps;
  return c;
}

}  // namespace tessera
