#pragma once
// How far above its limit a block-coordinate solve stopped, from its own trace: the cost still
// to come if the rounds went on at the rate of their last ones. `--refine auto` refines only
// where this says the rounds stopped short (NewtonRefineOptions::When::kIfRoundsSlow).
//
// Why a tail and not the gradient: on long chains the rounds stop at gradient 0.01 far above
// f* (parking-garage 6.8e-4, ais2klinik 1.8e-4 relative), on the other paper graphs within
// 3.4e-7 at the same gradient: the stiff modes set the gradient, the slow ones the gap. The
// slow modes show as a cost that still falls round after round.

#include <tessera/distributed/round_history.hpp>
#include <vector>

namespace tessera {

/// The relative gap the rounds of `trace` would still close, estimated from the cost decreases
/// of the last `window` rounds (d1) and of the `window` before them (d0) as a geometric tail,
/// d1 q / (1 - q) with q = d1 / d0 capped at `max_rate` (a rate at or above the cap is read as
/// the cap: a noisy pair of windows must not make the estimate unbounded), divided by
/// max(1, |f|) at the last round. +infinity when the trace has fewer than 2 window + 1 records
/// (too short to tell); 0 when the last window did not lower the cost. window >= 1,
/// max_rate in (0, 1).
double rounds_tail_gap(const std::vector<RoundRecord>& trace, int window, double max_rate);

}  // namespace tessera
