#pragma once
// The certificate's weak-duality bound (core's dual_bound.hpp) in the summaries: the same JSON
// fields and text line for `tessera solve` (centralized and distributed) and the coordinator's
// summary of `tessera launch`, so the three keep one public format.

#include <string>
#include <tessera/certification/dual_bound.hpp>

#include "json_writer.hpp"

namespace tessera::cli {

/// Appends, for an estimate of cost `rounded_cost`:
///   certificate_method          "exact" (a factorization proved the bound) or "lobpcg" (the
///                               distributed estimate without the interface test: no bound)
///   dual_lower_bound            f_lb, a proved lower bound on the optimum f* (null: not proved)
///   suboptimality_bound         rounded_cost - f_lb: the estimate is at most this above f*
///   relative_suboptimality_bound  that over max(1, |f(Y)|)
///   relaxation_suboptimality_bound  f(Y) - f_lb (what `certified` compares with the tolerance)
///   certificate_grad_norm       |grad f| at the certified point Y
///   certificate_shift           the mean shift s_i of the proved S + D > 0 (null: none)
/// (nulls when the certificate did not run: every field NaN).
void add_certificate_bound(JsonObject& j, const DualBound& bound, double rounded_cost);

/// One line: "lower bound f_lb (proved at s), estimate at most X (Y relative) above the
/// optimum, |grad f| G at the certified point", or why there is no bound.
std::string certificate_bound_line(const DualBound& bound, double rounded_cost);

}  // namespace tessera::cli
