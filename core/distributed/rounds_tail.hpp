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
/// max(1, |f|) at the last round; 0 when the last window did not lower the cost. A trace of
/// fewer than 2 window + 1 records (the rounds stopped within 2 window - 1 rounds, which at a
/// loose gradient tolerance happens far above f*) is read as its last floor(k / 2) rounds'
/// decrease (at least one round; k = rounds) at the rate max_rate: a rate from so few rounds
/// is not trusted. At `--grad-tol 1` and 0.1 this was above the true gap on the short traces
/// measured (CSAIL 8 rounds: 1.4e-4 against 2.9e-5; parking-garage 2 and 4 rounds: 0.37 and
/// 1.1e-2 against 2.9e-3 and 2.2e-3), where the two windows' rate read from the same rounds
/// said 6.5e-7, 4.6e-2 and 1.2e-5. A trace of one record (no round: the start met the
/// tolerance) gives 0: no round, no sign of slow ones. window >= 1, max_rate in (0, 1).
double rounds_tail_gap(const std::vector<RoundRecord>& trace, int window, double max_rate);

}  // namespace tessera
