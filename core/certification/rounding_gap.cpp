#include <algorithm>
#include <cmath>
#include <tessera/certification/rounding_gap.hpp>

namespace tessera {

double relative_rounding_gap(double rounded_cost, double relaxation_cost) {
  return (rounded_cost - relaxation_cost) / std::max(1.0, std::abs(relaxation_cost));
}

bool rounding_is_tight(double rounded_cost, double relaxation_cost, double tolerance) {
  return relative_rounding_gap(rounded_cost, relaxation_cost) <= tolerance;
}

std::optional<bool> estimate_certified(std::optional<bool> relaxation_certified,
                                       double rounded_cost, double relaxation_cost) {
  if (relaxation_certified && *relaxation_certified &&
      !rounding_is_tight(rounded_cost, relaxation_cost))
    return false;
  return relaxation_certified;
}

}  // namespace tessera
