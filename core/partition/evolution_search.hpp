#pragma once
// Internal: one population of the memetic search (evolutionary.hpp), advanced in steps.
//
// Why in steps: the island model (island_search.hpp) has to stop every population at fixed
// step counts, hand individuals between them and resume, so the population and its loop state
// live here and run() advances them by a given number of steps. Run without interruption (one
// island) it draws exactly the random numbers of one uninterrupted loop, so a seed gives the
// same partition whether or not the search runs in steps.

#include <vector>

#include "partition/evolutionary.hpp"

namespace tessera::partition_detail {

struct Individual {
  std::vector<int> part;
  long long cut = 0;
};

class EvolutionSearch {
 public:
  /// Keeps references to g, ub, params and rng: they must outlive the search. Nothing is
  /// computed until build_population().
  EvolutionSearch(const WorkGraph& g, int k, const std::vector<long long>& ub,
                  const EvolutionParams& params, Rng& rng);

  /// Builds the initial population (params.population multilevel runs, each followed by
  /// params.vcycles V-cycles). Must be called once before run().
  void build_population();

  /// Runs up to max_steps combine / mutation steps. Returns false once the search has ended
  /// (step budget spent, stall limit reached and its light tail done, or a population of 1);
  /// later calls then do nothing.
  bool run(int max_steps);

  /// Offers an individual found elsewhere: taken only when its cut is below the population's
  /// best, then it replaces the worst individual and resets the stall count, as a new best
  /// child would. Otherwise nothing changes (not even the generator's state), so a search that
  /// is ahead continues exactly as on its own. Returns whether it was taken.
  bool offer(const Individual& ind);

  bool ended() const { return ended_; }
  const Individual& best() const;
  int steps() const { return steps_; }
  int improved() const { return improved_; }
  /// The step (1-based) that found the current best; 0 = the initial population's.
  int last_improved_step() const { return last_improved_step_; }
  int population_size() const { return static_cast<int>(pop_.size()); }

 private:
  bool step();
  bool insert(Individual child, bool* new_best);
  std::vector<int> fresh_partition(const std::vector<int>* like);
  Individual fresh_individual();

  const WorkGraph& g_;
  int k_;
  const std::vector<long long>& ub_;
  const EvolutionParams& params_;
  Rng& rng_;
  std::vector<Individual> pop_;
  int gen_ = 0, steps_ = 0, improved_ = 0, stalled_ = 0, last_improved_step_ = 0;
  int tail_ = -1;  ///< light-only steps left (-1: not started)
  bool ended_ = false;
};

/// Improves `ind` by a V-cycle that keeps its blocks contractible (never worse).
Individual vcycle(const WorkGraph& g, int k, const std::vector<long long>& ub, Individual ind,
                  const CycleParams& cp, Rng& rng);

/// Guided V-cycle on the better parent contracting only what both parents share (never worse
/// than the better parent).
Individual combine(const WorkGraph& g, int k, const std::vector<long long>& ub, const Individual& a,
                   const Individual& b, const CycleParams& cp, Rng& rng);

/// The cycle parameters of one operation: flow corridor alpha or 2 alpha, and with probability
/// params.matching_share heavy-edge matching instead of label propagation.
CycleParams varied(const EvolutionParams& params, Rng& rng);

}  // namespace tessera::partition_detail
