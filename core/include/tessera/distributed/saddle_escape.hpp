#pragma once
// Distributed saddle escape of the Riemannian staircase (SE-Sync style), one agent's state
// machine. At a rank-r critical point Y whose certificate found a direction v with
// v^T S v < 0, the point [Y; 0] is a critical point at rank r + 1 and [0; v^T] is a tangent
// direction of negative curvature there. A backtracking line search on the global cost:
//   Y+(alpha) = retract([Y; 0] + alpha [0; v^T]),  alpha = alpha0, alpha0/2, ...
// accepted when f(Y+) < f(Y) and ||grad f(Y+)|| > the solver's tolerance (so the solve that
// follows does not stop at once). Per trial: one neighbour exchange of the boundary poses of
// Y+ and one global reduction (cost share, squared gradient norm), summed in agent-id order.
// alpha0 = 100 sqrt(n) and the halving match the centralized escape, so both try the same
// steps.

#include <Eigen/Core>
#include <cstdint>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <vector>

namespace tessera {

struct SaddleEscapeOptions {
  int max_trials = 80;  ///< Halvings of alpha before giving up. > 0
  void validate() const;
};

struct SaddleEscapeResult {
  bool success = false;
  int trials = 0;      ///< Line-search trials (each: one exchange, one reduction).
  double alpha = 0.0;  ///< Accepted step.
  double cost = 0.0;   ///< f(Y+) (global, as summed by every agent).
  double grad_norm = 0.0;
  Eigen::MatrixXd Y;   ///< Own block of Y+ at rank r + 1.
  Eigen::MatrixXd Yn;  ///< Neighbours' boundary poses of Y+.
};

class SaddleEscapeProtocol : public AgentProcess {
 public:
  /// `state` at the rank-r point (Y, Yn); `direction`: this agent's block (1 x (d+1)m) of the
  /// unit eigenvector; `cost` = f(Y) as every agent summed it; `grad_tol`: see above.
  SaddleEscapeProtocol(const AgentState& state, const BlockLayout& layout,
                       const Eigen::MatrixXd& direction, double cost, double grad_tol,
                       const SaddleEscapeOptions& options);

  std::vector<OutgoingMessage> start() override;
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  const SaddleEscapeResult& result() const { return result_; }

 private:
  enum Step : std::uint32_t { kPoses = 1, kStatus = 2 };
  void trial(std::vector<OutgoingMessage>& out);
  void pump(std::vector<OutgoingMessage>& out);

  const AgentState& state_;
  const BlockLayout& layout_;
  BlockProblem problem_;  // own copy, evaluated at rank r + 1
  Eigen::MatrixXd Ya_, dir_;
  double f0_, grad_tol_;
  SaddleEscapeOptions options_;
  double alpha_ = 0.0;
  std::uint32_t trial_ = 0;
  Eigen::MatrixXd Xp_, Xpn_;
  MessageGate gate_;
  bool done_ = false;
  SaddleEscapeResult result_;
};

}  // namespace tessera
