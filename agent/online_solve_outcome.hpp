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
};

}  // namespace tessera::agent
