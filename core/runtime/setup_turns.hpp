#pragma once
// Turns for the initialisation's local solves: how many agents factorize at once.
//
// In the distributed initialisation every robot first solves the chordal relaxation of its own
// measurements (robot_units): a sparse factorization whose fill grows like m^(4/3) in the
// block's m poses (~270 MB on a 31,250-pose 3D block). Run by all agents of a host at once
// this is the set-up's peak (64 agents of a 2M-pose grid: ~17 GB), while on a few cores they
// share the CPU anyway, so running them a few at a time costs little wall time.
//
// The rule: with K = max_at_once, agent a waits until agent a - K has finished its local
// solve (it tells a + K when it has). The agents form K chains by a mod K, each chain one at a
// time, so at most K agents are in their local solve at once and no agent waits for a later
// one (no cycle). Nothing but that one message per agent is added.

#include <cstdint>
#include <functional>
#include <optional>

namespace tessera::agent {

struct SetupTurnOptions {
  /// At most this many agents in their local solve at once; 0 = all at once (no turns).
  /// Valid: 0..kMaxSetupAtOnce.
  std::uint32_t max_at_once = 0;
  /// Called by an agent when its local solve is done and freed, before it gives the turn on:
  /// e.g. the agent hands its freed heap back to the kernel (malloc_trim), so what the next
  /// agent factorizes does not add to memory this one still holds. May be empty.
  std::function<void()> after_local_solve;

  static constexpr std::uint32_t kMaxSetupAtOnce = 1000;
  /// Throws InputError naming max_at_once when it is out of range.
  void validate() const;
};

/// One agent's place in the turns.
struct SetupTurn {
  std::optional<std::uint32_t> waits_for;  ///< the agent whose done message starts our solve
  std::optional<std::uint32_t> passes_to;  ///< the agent we tell when ours is done
  std::uint32_t position = 0;              ///< solves before ours in our chain
  std::uint32_t chain_length = 1;          ///< solves in the longest chain (turns of the stage)
};

/// Agent `self`'s turn among `num_agents` (self < num_agents) at `max_at_once` (0 = all).
SetupTurn setup_turn(std::uint32_t self, std::uint32_t num_agents, std::uint32_t max_at_once);

}  // namespace tessera::agent
