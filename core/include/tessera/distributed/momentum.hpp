#pragma once
// The shape shared by the accelerated methods (RBCD++ and IRBCD). Each round k, with global
// scalars (alpha_k, beta_k, gamma_k) computed identically by every agent:
//   P^k     = Proj_M(alpha_k V^k + (1 - alpha_k) Y^k)                     (extrapolated point)
//   Y^{k+1} = block update of the selected block(s) from P^k, neighbours at P^k;
//             unselected blocks keep Y^k or take P^k (scheme option)
//   V^{k+1} = Proj_M(beta_k V^k + (1 - beta_k) P^k + gamma_k (Y^{k+1} - P^k))
// and an adaptive restart: if f(Y^k) - f(Y^{k+1}) < c ||grad f(Y^k)||^2, the round is redone
// from Y^k (plain block update, neighbours at Y^k) and V^{k+1} = Y^{k+1}.
// Every operation above is pose-wise, so each agent applies it to its own block alone.

#include <Eigen/Core>
#include <memory>
#include <tessera/distributed/block_selection.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <vector>

namespace tessera {

struct MomentumCoefficients {
  double alpha = 1.0;
  double beta = 1.0;
  double gamma = 0.0;
};

class MomentumScheme {
 public:
  virtual ~MomentumScheme() = default;
  virtual std::unique_ptr<MomentumScheme> clone() const = 0;
  /// The coefficients of the current round.
  virtual MomentumCoefficients coefficients() const = 0;
  /// Moves the scalar recurrences to the next round.
  virtual void advance() = 0;
  /// Called after a restart.
  virtual void restart() = 0;
  /// Unselected blocks take P^k (true) or keep Y^k (false).
  virtual bool unselected_take_extrapolation() const = 0;
  /// Restart constant c (< 0: never restart).
  virtual double restart_constant() const = 0;
  /// How greedy selection scores a colour class in parallel rounds (block_selection.hpp).
  /// RBCD++ keeps the shared rule; IRBCD makes it an option (IrbcdOptions::class_score).
  virtual ClassScore class_score() const { return ClassScore::kLargestBlock; }
  /// The scalar recurrences' current values (for checkpoints), and restoring them: after
  /// load(save()) the scheme produces the same coefficients as the one saved.
  virtual std::vector<double> save() const = 0;
  /// Throws std::runtime_error when `state` does not have this scheme's size.
  virtual void load(const std::vector<double>& state) = 0;
};

/// Proj_M(X): each pose's Stiefel part replaced by its polar factor (equal to
/// LiftedManifold::project to round-off, several times cheaper near the manifold).
Eigen::MatrixXd project_to_manifold(const LiftedManifold& M, Eigen::MatrixXd X);

/// Proj_M(alpha V + (1 - alpha) Y).
Eigen::MatrixXd extrapolate(const LiftedManifold& M, const MomentumCoefficients& c,
                            const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V);

/// Proj_M(beta V + (1 - beta) P + gamma (Y_new - P)).
Eigen::MatrixXd momentum_update(const LiftedManifold& M, const MomentumCoefficients& c,
                                const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                                const Eigen::MatrixXd& Y_new);

/// The same two into `out`, bit-identical to the functions above, computed pose by pose in
/// out's storage (no allocation when out already has the shape). `out` may be one of the
/// inputs (the round protocol updates V in place). Throws std::invalid_argument when the
/// inputs' shapes differ.
void extrapolate_into(const LiftedManifold& M, const MomentumCoefficients& c,
                      const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V, Eigen::MatrixXd& out);
void momentum_update_into(const LiftedManifold& M, const MomentumCoefficients& c,
                          const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                          const Eigen::MatrixXd& Y_new, Eigen::MatrixXd& out);

}  // namespace tessera
