#include "distributed/momentum.hpp"

namespace tessera {

Eigen::MatrixXd extrapolate(const LiftedManifold& M, const MomentumCoefficients& c,
                            const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V) {
  return M.project(c.alpha * V + (1.0 - c.alpha) * Y);
}

Eigen::MatrixXd momentum_update(const LiftedManifold& M, const MomentumCoefficients& c,
                                const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                                const Eigen::MatrixXd& Y_new) {
  return M.project(c.beta * V + (1.0 - c.beta) * P + c.gamma * (Y_new - P));
}

}  // namespace tessera
