#pragma once
// RBCD++ (Tian, Khosoussi, Rosen, How: Nesterov-accelerated RBCD with adaptive restart), in
// the form of momentum.hpp with n selectable units (blocks, or colour classes when parallel):
//   gamma_k = (1 + sqrt(1 + 4 n^2 gamma_{k-1}^2)) / (2 n),  gamma_{-1} = 0 (and after a restart)
//   alpha_k = 1 / (n gamma_k),  beta_k = 1   (so V^{k+1} = Proj(V^k + gamma_k (Y^{k+1} - P^k)))
//   unselected blocks take P^k.

#include <tessera/distributed/momentum.hpp>

namespace tessera {

struct RbcdPlusPlusOptions {
  /// Restart when f(Y^k) - f(Y^{k+1}) < restart_c ||grad f(Y^k)||^2; < 0 disables restarts.
  double restart_c = 0.0;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

class RbcdPlusPlusScheme : public MomentumScheme {
 public:
  RbcdPlusPlusScheme(const RbcdPlusPlusOptions& options, int units);
  std::unique_ptr<MomentumScheme> clone() const override;
  MomentumCoefficients coefficients() const override;
  void advance() override;
  void restart() override;
  bool unselected_take_extrapolation() const override { return true; }
  double restart_constant() const override { return options_.restart_c; }
  std::vector<double> save() const override;
  void load(const std::vector<double>& state) override;

 private:
  RbcdPlusPlusOptions options_;
  double n_;
  double gamma_prev_ = 0.0;
};

}  // namespace tessera
