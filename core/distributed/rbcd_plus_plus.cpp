#include <cmath>
#include <stdexcept>
#include <string>
#include <tessera/distributed/rbcd_plus_plus.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void RbcdPlusPlusOptions::validate() const {
  if (!std::isfinite(restart_c)) throw InputError("RbcdPlusPlusOptions.restart_c must be finite");
}

RbcdPlusPlusScheme::RbcdPlusPlusScheme(const RbcdPlusPlusOptions& options, int units)
    : options_(options), n_(static_cast<double>(units)) {
  options_.validate();
}

std::unique_ptr<MomentumScheme> RbcdPlusPlusScheme::clone() const {
  return std::make_unique<RbcdPlusPlusScheme>(*this);
}

MomentumCoefficients RbcdPlusPlusScheme::coefficients() const {
  const double g = (1.0 + std::sqrt(1.0 + 4.0 * n_ * n_ * gamma_prev_ * gamma_prev_)) / (2.0 * n_);
  MomentumCoefficients c;
  c.gamma = g;
  c.alpha = 1.0 / (n_ * g);
  c.beta = 1.0;
  return c;
}

void RbcdPlusPlusScheme::advance() {
  gamma_prev_ = coefficients().gamma;
}

void RbcdPlusPlusScheme::restart() {
  gamma_prev_ = 0.0;
}

std::vector<double> RbcdPlusPlusScheme::save() const {
  return {gamma_prev_};
}

void RbcdPlusPlusScheme::load(const std::vector<double>& state) {
  if (state.size() != 1)
    throw std::runtime_error("RbcdPlusPlusScheme: saved state has " + std::to_string(state.size()) +
                             " values, expected 1");
  gamma_prev_ = state[0];
}

}  // namespace tessera
