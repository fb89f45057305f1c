#pragma once
// Internal: the island model of the memetic search (KaFFPaE's parallel scheme, made
// deterministic).
//
// One population converges into one global arrangement of the blocks, and on some graphs the
// arrangement decides the cut: rim's partitions fall into basins (seeds 1-6 of one search
// reached 258/266/243/243/259/264, every 243 with a light block of 1867 vertices), and no
// refinement or search setting moved a seed from one basin into the other (docs/partitioning.md).
// Several populations, each with the full budget and its own generator, reach more arrangements
// for the same wall time on a multi-core machine; exchanging their best individuals now and
// then lets the better arrangement also take the other island's refinement effort. A migrant
// enters a population only when it beats that population's best, so an island that is ahead
// is never disturbed.
//
// Determinism: the number of islands is an option, never hardware_concurrency, and the islands
// meet only at fixed step counts (every `exchange_every` steps each one stops, all are joined,
// each receives the others' best as it was at that moment), so thread timing never changes
// what any island sees. Island 0 draws from the caller's generator exactly as the single search
// did, so up to its first exchange it is that search step for step.

#include <functional>
#include <string>
#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct EvolutionParams;

struct IslandOptions {
  /// Populations searched concurrently, each on its own thread with the whole budget of
  /// EvolutionParams (population, generations, stall limit...). 1 = the single search on the
  /// calling thread, no thread started. Range 1..8.
  int islands = 1;
  /// Steps (combine / mutation operations of one island) between two exchanges; 0 = the
  /// islands never exchange and only their best results are compared at the end. Range >= 0.
  int exchange_every = 0;
  /// When >= 0, island 1 coarsens by heavy-edge matching in this share of its operations
  /// instead of EvolutionParams::matching_share (a differently configured second search);
  /// -1 = every island uses the same parameters. Range -1 or 0..1.
  double second_matching_share = -1.0;
  /// Further islands after the `islands` full ones, each with only `short_budget` of the step
  /// budget (EvolutionParams::generations; the same population), each on its own thread. Island
  /// i keeps its generator whatever the count, so a short island is the first steps of the full
  /// island i would be. A cheap further draw of the arrangement lottery. Range 0..8.
  int short_islands = 0;
  /// Share of the step budget of each short island. Range (0, 1].
  double short_budget = 0.5;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

struct IslandSearchResult {
  std::vector<int> part;  ///< The best partition over all islands (ties: lowest island).
  long long cut = 0;
};

/// The step budget (EvolutionParams::generations) of each short island: short_budget of the
/// full islands' `generations`, at least 1.
int short_island_generations(int generations, double short_budget);

/// Runs params.islands.islands (+ short_islands) populations of the memetic search
/// (evolution_search.hpp) under `ub` and returns the best partition found. Island 0 uses `rng`
/// (which it advances); island i > 0 a generator derived from rng's state and i. Exceptions thrown
/// in an island are rethrown here after all threads have been joined. `trace` (may be empty) is
/// called on the calling thread after the initial populations ("population") and after the search
/// ("evolution"; per island: steps, improvements and the step of the last one, migrants taken,
/// best cut, thread CPU time; and each thread's CPU time). Every island runs on its own thread
/// (the caller's is one of them); `side_jobs` (may be empty; work independent of the search that
/// the caller needs afterwards anyway) run after them in whichever thread is free first. Which
/// thread runs what never changes a result.
IslandSearchResult island_search(
    const WorkGraph& g, int k, const std::vector<long long>& ub, const EvolutionParams& params,
    Rng& rng, const std::function<void(const std::string&, const std::string&, long long)>& trace,
    const std::vector<std::function<void()>>& side_jobs = {});

}  // namespace tessera::partition_detail
