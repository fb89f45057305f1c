#pragma once
// Internal: a small memetic (evolutionary + multilevel) search in the style of KaHIP's KaFFPaE:
// a population of multilevel partitions improved by combine operations (a guided V-cycle that
// only contracts vertices the two parents put in the same blocks, started from the better
// parent, so a child is never worse than it) and mutations (V-cycles and combines with fresh
// partitions). Everything is counted in operations, not seconds, so a seed fixes the result.

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "partition/block_resplit.hpp"
#include "partition/island_search.hpp"
#include "partition/multilevel.hpp"
#include "partition/relaxed_polish.hpp"
#include "partition/spectral_layouts.hpp"

namespace tessera::partition_detail {

struct EvolutionParams {
  int population = 6;          ///< Individuals built by independent multilevel runs (+ V-cycles).
  int vcycles = 1;             ///< Guided V-cycles applied to each new individual.
  int generations = 20;        ///< Combine / mutation steps after the initial population.
  int stall_limit = 1 << 30;   ///< Stop after this many steps without a new best cut.
  double mutation_rate = 0.3;  ///< Share of steps that combine with a fresh partition instead.
  /// Share of operations (fresh runs, V-cycles, combines) that coarsen by heavy-edge matching
  /// instead of the label propagation of `cycle`: the two give differently shaped hierarchies,
  /// and mixing them keeps the population diverse (0 = always `cycle`'s coarsening).
  double matching_share = 0.0;
  int matching_flow_levels = 1;  ///< flow_levels of the operations that coarsen by matching.
  /// Share of steps that cross-combine a tournament winner with a fresh partition into another
  /// number of blocks (KaFFPaE's cross combine) instead of a combine or mutation.
  double cross_share = 0.0;
  /// Cross combines only start once this many steps in a row found no new best cut.
  int cross_after_stall = 0;
  /// Share of fresh partitions (initial population and mutations) built under bounds that force
  /// one block to be light (light_block.hpp); the search then also starts from shapes with one
  /// light block and the others at the bound, which the uniform bound rarely reaches.
  double light_share = 0.0;
  /// Share of steps that instead V-cycle a tournament winner under such bounds and then once
  /// more under the real bounds (a perturbation towards a light block).
  double light_cycle_share = 0.0;
  int light_after_stall = 0;  ///< Light-block V-cycles only start after this many stalled steps.
  /// When the search stops on the stall limit before its step budget is spent, up to this many
  /// more steps (within the budget) are light-block V-cycles only: the unused budget goes into
  /// pushing the converged population towards one-light-block shapes. Until then the search
  /// runs exactly as without it, and the best cut can only get better.
  int light_tail = 0;
  double light_min = 0.88;  ///< Range of the light block's bound, as a fraction of the
  double light_max = 0.98;  ///< average block weight (raised where infeasible).
  /// After the search, its best partition gets this relax / repair refinement
  /// (relaxed_polish.hpp; never worse; rounds = 0: off). It draws from its own generator,
  /// seeded from a copy of the search's.
  RelaxedPolishOptions polish;
  /// Populations searched concurrently (island_search.hpp), each with all of the above budget;
  /// the polish and the spectral layouts then start from the best island's best. The default
  /// (1 island) is the single search on the calling thread.
  IslandOptions islands;
  /// Spectral layouts (spectral_layouts.hpp): after the search, the best this many refined
  /// global layouts read off the Laplacian embedding are each combined with the search's best
  /// partition, which they replace when better (the search before is unchanged). Their first
  /// half (embedding, layouts, FM) runs beside the islands, on a generator seeded from the
  /// caller's before the search. 0 = off.
  int spectral_seeds = 0;
  /// ...only those whose cut after FM is within this fraction above the search's best.
  double spectral_gap = 0.0;
  SpectralLayoutOptions spectral;
  /// Last (after the polish and the spectral layouts): sub-searches that keep the best
  /// partition's most separable blocks and search the rest again (block_resplit.hpp); the
  /// result replaces the best only when strictly better. searches = 0: off.
  BlockResplitOptions resplit;
  CycleParams cycle;
  /// Wall-clock cap: no step starts after it, the population stops growing (at least one
  /// individual), and the phases after the search (polish, spectral layouts, re-split) are
  /// skipped. The default never comes; with a real deadline the result depends on the machine.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  bool past_deadline() const { return std::chrono::steady_clock::now() >= deadline; }

  /// Throws InputError naming the first field out of range (the polish and spectral options
  /// included; the cycle's parameters are the presets' own).
  void validate() const;
};

/// Called after each phase with (phase name, detail, best cut so far).
using EvolutionTrace = std::function<void(const std::string&, const std::string&, long long)>;

/// Returns the best partition found. With params.islands.islands > 1 the islands run on their
/// own threads; the result still depends only on the inputs and the generator's state.
std::vector<int> evolve(const WorkGraph& g, int k, const std::vector<long long>& ub,
                        const EvolutionParams& params, Rng& rng, const EvolutionTrace& trace);

}  // namespace tessera::partition_detail
