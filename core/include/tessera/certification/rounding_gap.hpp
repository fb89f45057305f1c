#pragma once
// When a certificate speaks for the rounded estimate, not only for the lifted X.
//
// The certificate proves X globally optimal for the SDP relaxation, so f(X) is a lower bound
// on the pose-graph optimum and cost(rounded) - f(X) bounds how far the rounded estimate can be
// from it. On the exact relaxations of usual pose graphs that bound is zero to rounding error
// (the rounded cost is at or below f(X) to 1e-9 relative on the shared datasets). A relaxation
// that is not tight (heavy noise, or outliers a robust run kept) certifies X but leaves the
// estimate many times above f(X): then the estimate is not certified.

#include <optional>

namespace tessera {

/// Default bound on (rounded_cost - relaxation_cost) / max(1, |relaxation_cost|) for a
/// certificate to carry over to the rounded estimate.
inline constexpr double kDefaultRoundingGapTolerance = 1e-5;

/// (rounded_cost - relaxation_cost) / max(1, |relaxation_cost|): the rounded estimate's
/// relative suboptimality bound when the relaxation is certified (negative when rounding ended
/// below f(X), which happens when X stopped before its exact critical point).
double relative_rounding_gap(double rounded_cost, double relaxation_cost);

/// True when the certificate of the relaxation also certifies the rounded estimate: the
/// relative rounding gap is at most `tolerance` (>= 0).
bool rounding_is_tight(double rounded_cost, double relaxation_cost,
                       double tolerance = kDefaultRoundingGapTolerance);

/// The estimate's verdict from the relaxation's: a certified relaxation whose rounding is not
/// tight (rounding_is_tight) leaves the estimate uncertified; anything else passes unchanged
/// (no certificate stays none, false stays false). Every solver's `certified` goes through this.
std::optional<bool> estimate_certified(std::optional<bool> relaxation_certified,
                                       double rounded_cost, double relaxation_cost);

}  // namespace tessera
