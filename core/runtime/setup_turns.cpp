#include "runtime/setup_turns.hpp"

#include <stdexcept>
#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::agent {

void SetupTurnOptions::validate() const {
  if (max_at_once > kMaxSetupAtOnce)
    throw InputError("SetupTurnOptions::max_at_once: " + std::to_string(max_at_once) +
                     " is not in 0.." + std::to_string(kMaxSetupAtOnce));
}

SetupTurn setup_turn(std::uint32_t self, std::uint32_t num_agents, std::uint32_t max_at_once) {
  if (self >= num_agents)
    throw std::invalid_argument("setup_turn: agent " + std::to_string(self) + " of " +
                                std::to_string(num_agents));
  const std::uint32_t k = max_at_once == 0 || max_at_once >= num_agents ? num_agents : max_at_once;
  SetupTurn t;
  if (self >= k) t.waits_for = self - k;
  if (self + k < num_agents) t.passes_to = self + k;
  t.position = self / k;
  t.chain_length = (num_agents + k - 1) / k;
  return t;
}

}  // namespace tessera::agent
