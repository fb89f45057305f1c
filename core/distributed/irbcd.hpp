#pragma once
// IRBCD, Algorithm 1 of the reference paper (Nesterov's accelerated coordinate descent
// recurrences carried to the manifold by Proj_M), in the form of momentum.hpp:
//   gamma_k >= 1/n solves gamma^2 - gamma/n = (1 - gamma sigma/n) a_k^2 / b_k^2
//   alpha_k = (n - gamma_k sigma) / (gamma_k (n^2 - sigma)),  beta_k = 1 - gamma_k sigma / n
//   b_{k+1} = b_k / sqrt(beta_k),  a_{k+1} = gamma_k b_{k+1}
// The paper's open points are options; defaults chosen by measurement (docs/irbcd.md).

#include <string>

#include "distributed/momentum.hpp"

namespace tessera {

/// What n means in the recurrences.
enum class IrbcdDimension {
  kUnits,     ///< Number of selectable units: blocks (colour classes when parallel).
  kVariables  ///< Number of scalar variables r (d+1) num_poses.
};

struct IrbcdOptions {
  /// Strong-convexity estimate ("rho" read as sigma); >= 0, < n^2. 1e-4 rather than the
  /// paper's 1e-3: with parallel rounds fewer rounds on 10 of 13 benchmark graphs (kitti_00
  /// 936 vs 2170), more on intel and MIT (+8%, +12%); docs/irbcd.md section 9.
  double sigma = 1e-4;
  double a0 = 0.0;  ///< Initial a; <= 0 means 1/n (the paper).
  double b0 = 1.0;  ///< Initial b, > 0.
  IrbcdDimension dimension = IrbcdDimension::kUnits;
  /// Unselected blocks take P^k (as in accelerated coordinate descent) instead of keeping Y^k.
  bool unselected_take_extrapolation = true;
  /// c1 of the restart rule; < 0 disables restarts.
  double restart_c = 0.0;
  /// After a restart, reset a and b to a0, b0 (else keep the recurrences running).
  bool reset_on_restart = true;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

const char* dimension_name(IrbcdDimension d);
IrbcdDimension parse_dimension(const std::string& name);

/// gamma >= 1/n solving gamma^2 - gamma/n = (1 - gamma sigma/n) q, q = a^2/b^2 (the larger root).
double irbcd_gamma(double n, double sigma, double a, double b);

class IrbcdScheme : public MomentumScheme {
 public:
  /// `n`: units or variables, per options.dimension (the caller passes the right one).
  IrbcdScheme(const IrbcdOptions& options, double n);
  std::unique_ptr<MomentumScheme> clone() const override;
  MomentumCoefficients coefficients() const override;
  void advance() override;
  void restart() override;
  bool unselected_take_extrapolation() const override {
    return options_.unselected_take_extrapolation;
  }
  double restart_constant() const override { return options_.restart_c; }
  std::vector<double> save() const override;
  void load(const std::vector<double>& state) override;
  double a() const { return a_; }
  double b() const { return b_; }

 private:
  void reset();
  IrbcdOptions options_;
  double n_;
  double a_, b_;
};

}  // namespace tessera
