#pragma once
// The outcome of one solve of an online epoch's graph by this agent's block.

#include <optional>
#include <string>

namespace tessera::agent {

struct SolveOutcome {
  int rounds = 0;
  double grad_norm = 0.0;
  std::string stop_reason;
  std::optional<bool> certified;
  double min_eigenvalue = 0.0;
  std::optional<double> relaxation_cost;  ///< f of the last lifted iterate (summed over agents).
  /// The Newton steps (accepted or not), their CG iterations and message steps, as the
  /// in-process engine counts them (OnlineUpdate); the largest coarse space they used (0: none,
  /// e.g. block Jacobi or robots that have not met).
  int newton_steps = 0, newton_cg_iterations = 0, newton_message_steps = 0;
  int coarse_unknowns = 0;
};

}  // namespace tessera::agent
