#pragma once
// Internal: local improvement of a k-way partition on one level of the hierarchy.

#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct FmParams {
  int max_passes = 3;         ///< FM passes per call; stops early when a pass finds no improvement.
  int stop_after = 60;        ///< A pass ends after this many moves without a new best cut.
  int local_rounds = 0;       ///< Rounds of localized FM (searches from single boundary vertices).
  int local_stop_after = 20;  ///< Stopping rule of each localized search.
};

/// Block pairs that must not share an edge: k x k, row-major, 1 = forbidden (symmetric). The
/// colour pass (quotient_colouring.hpp) uses it to keep two blocks of one colour apart.
using ForbiddenPairs = std::vector<char>;

/// Boundary k-way Fiduccia–Mattheyses: repeatedly moves the unlocked boundary vertex with the
/// best gain to its best block whose weight stays within ub, accepting negative gains to climb
/// out of local minima, then rolls back to the best cut seen in the pass. Never increases the cut
/// and never puts a block above ub (blocks already above stay where they are or get lighter).
/// Returns the new cut.
/// `known_cut`: the cut of `part` when the caller has it (saves a scan of the graph), -1 = not
/// known. `forbidden` (optional): no move may join two forbidden blocks by an edge.
long long kway_fm(const WorkGraph& g, int k, std::vector<int>& part,
                  const std::vector<long long>& ub, const FmParams& params, Rng& rng,
                  long long known_cut = -1, const ForbiddenPairs* forbidden = nullptr);

/// Moves vertices out of blocks heavier than ub[b], choosing the moves that cost the least cut.
/// Returns true when every block ends within its bound (always possible with unit weights).
/// `forbidden` (optional): as for kway_fm; then it may fail where a move would break it.
bool rebalance(const WorkGraph& g, int k, std::vector<int>& part, const std::vector<long long>& ub,
               const ForbiddenPairs* forbidden = nullptr);

}  // namespace tessera::partition_detail
