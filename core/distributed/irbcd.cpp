#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tessera/distributed/irbcd.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void IrbcdOptions::validate() const {
  if (!(sigma >= 0 && std::isfinite(sigma)))
    throw InputError("IrbcdOptions.sigma must be finite and >= 0");
  if (!std::isfinite(a0)) throw InputError("IrbcdOptions.a0 must be finite");
  if (!(b0 > 0 && std::isfinite(b0))) throw InputError("IrbcdOptions.b0 must be finite and > 0");
  if (!std::isfinite(restart_c)) throw InputError("IrbcdOptions.restart_c must be finite");
  if (!(sigma_shrink > 0 && sigma_shrink <= 1))
    throw InputError("IrbcdOptions.sigma_shrink must be in (0, 1]");
  if (!(sigma_saturation > 0 && sigma_saturation <= 1))
    throw InputError("IrbcdOptions.sigma_saturation must be in (0, 1]");
  if (!(sigma_restart_theta > 0 && std::isfinite(sigma_restart_theta)))
    throw InputError("IrbcdOptions.sigma_restart_theta must be finite and > 0");
  if (!(sigma_min >= 0 && std::isfinite(sigma_min)))
    throw InputError("IrbcdOptions.sigma_min must be finite and >= 0");
  if (!(sigma_max >= sigma_min && std::isfinite(sigma_max)))
    throw InputError("IrbcdOptions.sigma_max must be finite and >= sigma_min");
  if (class_score != ClassScore::kLargestBlock && class_score != ClassScore::kClassNorm)
    throw InputError("IrbcdOptions.class_score must be largest_block or class_norm");
}

const char* dimension_name(IrbcdDimension d) {
  return d == IrbcdDimension::kUnits ? "units" : "variables";
}

IrbcdDimension parse_dimension(const std::string& name) {
  if (name == "units" || name == "blocks") return IrbcdDimension::kUnits;
  if (name == "variables") return IrbcdDimension::kVariables;
  throw InputError("IRBCD dimension '" + name + "' is not one of units, variables");
}

double irbcd_gamma(double n, double sigma, double a, double b) {
  // gamma^2 + gamma (sigma q - 1)/n - q = 0; the product of the roots is -q < 0, so exactly one
  // root is positive, and it exceeds 1/n because the left side is negative at 1/n when sigma < n^2.
  const double q = (a * a) / (b * b);
  const double p = (sigma * q - 1.0) / n;
  return 0.5 * (-p + std::sqrt(p * p + 4.0 * q));
}

IrbcdScheme::IrbcdScheme(const IrbcdOptions& options, double n)
    : options_(options), n_(n), sigma_(options.sigma) {
  options_.validate();
  if (!(n_ >= 1)) throw InputError("IRBCD: n must be >= 1");
  if (!(options_.sigma < n_ * n_)) throw InputError("IrbcdOptions.sigma must be < n^2");
  // A start value above the cap raises the cap: --sigma 1e-3 alone keeps meaning 1e-3.
  options_.sigma_max = std::max(options_.sigma_max, options_.sigma);
  reset();
}

std::unique_ptr<MomentumScheme> IrbcdScheme::clone() const {
  return std::make_unique<IrbcdScheme>(*this);
}

MomentumCoefficients IrbcdScheme::coefficients() const {
  const double sigma = sigma_;
  MomentumCoefficients c;
  c.gamma = irbcd_gamma(n_, sigma, a_, b_);
  c.alpha = (n_ - c.gamma * sigma) / (c.gamma * (n_ * n_ - sigma));
  c.beta = 1.0 - c.gamma * sigma / n_;
  return c;
}

void IrbcdScheme::advance() {
  const MomentumCoefficients c = coefficients();
  b_ = b_ / std::sqrt(c.beta);
  a_ = c.gamma * b_;
  // gamma's fixed point is 1/sqrt(sigma); near it the damping (beta < 1) holds the momentum.
  // Reaching it without a restart means f still decreased every round: allow more momentum.
  if (options_.adaptive_sigma && sigma_ > 0 &&
      c.gamma * std::sqrt(sigma_) >= options_.sigma_saturation)
    set_sigma(sigma_ * options_.sigma_shrink);
}

void IrbcdScheme::restart() {
  if (options_.adaptive_sigma) {
    // advance() ran for the rejected round, so a/b is that round's gamma: momentum of that
    // size increased f. Damp so that gamma settles at theta times it.
    const double gamma_r = a_ / b_;
    const double g = options_.sigma_restart_theta * gamma_r;
    set_sigma(1.0 / (g * g));
  }
  if (options_.reset_on_restart) reset();
}

void IrbcdScheme::set_sigma(double s) {
  // Also below n^2 (the recurrences' domain); NaN-safe: a non-finite value keeps the old one.
  s = std::min(std::max(s, options_.sigma_min), options_.sigma_max);
  s = std::min(s, 0.5 * n_ * n_);
  if (std::isfinite(s)) sigma_ = s;
}

void IrbcdScheme::reset() {
  b_ = options_.b0;
  if (options_.unit_first_gamma) {
    // gamma = 1 in gamma^2 - gamma/n = (1 - gamma sigma/n) a^2/b^2 (sigma < n, so > 0 inside).
    a_ = b_ * std::sqrt((1.0 - 1.0 / n_) / (1.0 - sigma_ / n_));
    if (!(a_ > 0)) a_ = 1.0 / n_;  // n = 1: gamma = 1/n = 1 already
    return;
  }
  a_ = options_.a0 > 0 ? options_.a0 : 1.0 / n_;
}

std::vector<double> IrbcdScheme::save() const {
  return {a_, b_, sigma_};
}

void IrbcdScheme::load(const std::vector<double>& state) {
  // 2 values: a snapshot from before adaptive sigma existed (sigma was the option's).
  if (state.size() != 2 && state.size() != 3)
    throw std::runtime_error("IrbcdScheme: saved state has " + std::to_string(state.size()) +
                             " values, expected 3 (or 2 from an older snapshot)");
  a_ = state[0];
  b_ = state[1];
  sigma_ = state.size() == 3 ? state[2] : options_.sigma;
}

}  // namespace tessera
