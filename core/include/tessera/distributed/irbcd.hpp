#pragma once
// IRBCD, Algorithm 1 of the reference paper (Nesterov's accelerated coordinate descent
// recurrences carried to the manifold by Proj_M), in the form of momentum.hpp:
//   gamma_k >= 1/n solves gamma^2 - gamma/n = (1 - gamma sigma/n) a_k^2 / b_k^2
//   alpha_k = (n - gamma_k sigma) / (gamma_k (n^2 - sigma)),  beta_k = 1 - gamma_k sigma / n
//   b_{k+1} = b_k / sqrt(beta_k),  a_{k+1} = gamma_k b_{k+1}
// The paper's open points are options; defaults chosen by measurement (docs/irbcd.md).

#include <string>
#include <tessera/distributed/momentum.hpp>

namespace tessera {

/// What n means in the recurrences.
enum class IrbcdDimension {
  kUnits,     ///< Number of selectable units: blocks (colour classes when parallel).
  kVariables  ///< Number of scalar variables r (d+1) num_poses.
};

struct IrbcdOptions {
  /// Strong-convexity estimate ("rho" read as sigma); >= 0, < n^2. 1e-4 rather than the
  /// paper's 1e-3: with parallel rounds fewer rounds on 10 of 13 benchmark graphs (kitti_00
  /// 936 vs 2170), more on intel and MIT (+8%, +12%); docs/irbcd.md section 3.
  double sigma = 1e-4;
  /// Initial a; <= 0 means 1/n (the paper's a_0). With b_0 = 1 the first gamma solves
  /// gamma^2 - gamma/n = (1 - gamma sigma/n) a_0^2: a_0 = 1 starts gamma at ~1.2 (n = 3) instead
  /// of the paper's (1 + sqrt 5)/(2n) ~ 0.54, i.e. the momentum starts where the paper's reaches
  /// after ~2n rounds (RBCD++ starts at 1/n). Default 1: equal or fewer rounds than 1/n on 8
  /// of 11 paper graphs (cubicle 172 vs 223, kitti_02 1259 vs 1362; docs/irbcd.md section 3).
  double a0 = 1.0;
  /// Instead of `a0`, start a where the first round's gamma is exactly 1 (the default):
  /// with V^0 = P^0 = Y^0, V^1 = P^0 + gamma_0 (Y^1 - P^0) is then the first iterate itself, so
  /// the momentum starts at what the first block updates found and does not extrapolate past
  /// it. a0 = 1 gives gamma_0 = 1.28 with two colour classes, and the overshoot cost
  /// parking-garage a round to the baseline's threshold (docs/benchmarks/rounds_vs_baseline.md).
  bool unit_first_gamma = true;
  double b0 = 1.0;  ///< Initial b, > 0.
  IrbcdDimension dimension = IrbcdDimension::kUnits;
  /// Unselected blocks take P^k (as in accelerated coordinate descent) instead of keeping Y^k.
  bool unselected_take_extrapolation = true;
  /// c1 of the restart rule; < 0 disables restarts.
  double restart_c = 0.0;
  /// After a restart, reset a and b to a0, b0 (true: as RBCD++ resets its gamma), or keep the
  /// recurrences running (false, the default). Keeping is safe only because sigma > 0 bounds
  /// gamma by 1/sqrt(sigma): the restart still discards the round and sets V := Y, but the
  /// momentum schedule is kept, which saved rounds on 9 of 11 paper graphs (docs/irbcd.md
  /// section 3).
  bool reset_on_restart = false;
  /// Greedy selection with parallel rounds: the colour class with the largest class gradient
  /// norm sqrt(sum_{B in class} ||grad_B f||^2) (kClassNorm), or the class of the block with the
  /// largest ||grad_B f|| (kLargestBlock, RBCD's and RBCD++'s rule). n counts colour classes,
  /// so the class is the coordinate unit of the recurrences and its own gradient norm is its
  /// Gauss-Southwell score. No message change: every agent already has every block's norm.
  /// One block per round: both are the same rule. docs/irbcd.md section 3.
  ClassScore class_score = ClassScore::kLargestBlock;

  /// Adaptive sigma (ours, not the paper's; docs/irbcd.md section 3). sigma is the
  /// strong-convexity estimate of Nesterov's ACDM, whose gamma settles at 1/sqrt(sigma). Two
  /// observations adjust it, both from quantities every agent already has (the round's gamma
  /// and the restart decision, itself computed from the reduced f), so all agents keep
  /// bit-identical values and no message changes:
  /// - gamma reaches `sigma_saturation` of its fixed point without a restart: the damping is
  ///   active while f still decreased every round, so the estimate is too large:
  ///   sigma *= sigma_shrink (gamma may grow further);
  /// - a restart after a round with gamma_r: momentum of that size increased f, so
  ///   sigma := 1 / (sigma_restart_theta gamma_r)^2 (gamma's new fixed point theta gamma_r;
  ///   always an increase, since gamma_r <= 1/sqrt(sigma)).
  /// sigma stays in [sigma_min, sigma_max]; `sigma` is the start value; sigma_max = 1e-4 (= the
  /// start) by default, so a restart can only undo earlier shrinks. Off by default: with the
  /// tangent preconditioner and a0 = 1 it acts only on the two longest paper runs and costs
  /// rounds there (kitti_02 1259 vs 1206; docs/irbcd.md section 3).
  bool adaptive_sigma = false;
  double sigma_shrink = 0.25;        ///< In (0, 1].
  double sigma_saturation = 0.9;     ///< In (0, 1].
  double sigma_restart_theta = 0.5;  ///< > 0.
  double sigma_min = 1e-8;           ///< >= 0.
  double sigma_max = 1e-4;           ///< >= sigma_min; raised to `sigma` if below it.

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// "units" or "variables"; parse_dimension(dimension_name(d)) == d.
const char* dimension_name(IrbcdDimension d);
/// The dimension named "units" (or its alias "blocks") or "variables"; throws InputError
/// naming any other value.
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
  ClassScore class_score() const override { return options_.class_score; }
  std::vector<double> save() const override;
  void load(const std::vector<double>& state) override;
  double a() const { return a_; }
  double b() const { return b_; }
  /// The current strong-convexity estimate (options.sigma unless adaptive_sigma).
  double sigma() const { return sigma_; }

 private:
  void reset();
  void set_sigma(double s);
  IrbcdOptions options_;
  double n_;
  double a_, b_;
  double sigma_;
};

}  // namespace tessera
