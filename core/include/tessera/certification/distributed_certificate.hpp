#pragma once
// Distributed verification of the global-optimality certificate (the distributed counterpart
// of certificate.hpp): the agents jointly estimate lambda_min(S) of S = Q - Lambda(X) without
// gathering the measurements. One agent's state machine (messages in -> messages out, no
// transport), driven like RoundProtocol.
//
// Each agent builds its own diagonal blocks Lambda_i = sym(Y_i^T (XQ)_i) from its own data and
// its neighbours' boundary poses. The eigen-solver is LOBPCG with one vector (locally optimal
// block preconditioned conjugate gradient, Knyazev 2001) on the vector [x, w, p]:
//   * S v needs, besides the agent's own entries, only the neighbours' boundary entries of v:
//     one neighbour exchange per iteration (of the preconditioned residual w; S x and S p are
//     carried along as the same combinations of S w).
//   * every inner product is a global reduction summed in agent-id order, so each agent solves
//     the same 3x3 Rayleigh-Ritz problem bit for bit and takes the same decisions.
//   * the preconditioner is block Jacobi: each agent factors its own diagonal block of S
//     (shifted until positive definite) once and applies it locally, no communication.
// The start vector is a hash of the GLOBAL pose ids, so it does not depend on the partition.
// It stops when the Ritz residual ||S x - theta x|| (||x|| = 1) is small, or at a cap.
// Certified iff converged and theta >= -eta, eta = relative_tolerance * max(1, max diag Q)
// (the centralized certificate's eta). theta is a Rayleigh quotient, so theta < -eta PROVES
// that S is not PSD; the Ritz vector (each agent its block) is then the escape direction.
//
// When the blocks' interfaces are small (interface_max_coordinates), the agents first test
// S + eta I > 0 exactly, by substructuring (interface_schur.hpp): one reduction (the global
// eta), each agent's Schur complement on its interface to agent 0, agent 0's factorization of
// the interface matrix and its verdict back: three message steps instead of LOBPCG's two an
// iteration (city10000: 149 iterations). The verdict is a proof either way. Certified, the
// reported lambda_min is the smallest Ritz value on the iterate's row space (S Y^T = 0 at a
// critical point), refined by LOBPCG from there only when its residual is above the tolerance.
// Not certified, LOBPCG runs as without the test, from the usual start, for the eigenvector
// of the escape.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <tessera/certification/dual_bound.hpp>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/problem/block_problem.hpp>
#include <vector>

namespace tessera {

enum class CertificatePreconditioner {
  kNone,        ///< Plain LOBPCG (identity preconditioner).
  kBlockJacobi  ///< Each agent's diagonal block of S, factored locally (default).
};

struct DistributedCertificateOptions {
  /// eta = relative_tolerance * max(1, max diagonal entry of Q), as the centralized one. >= 0.
  double relative_tolerance = 1e-6;
  /// Stop when ||S x - theta x|| <= residual_tolerance * max(1, max diag Q). > 0.
  double residual_tolerance = 1e-6;
  int max_iterations = 300;  ///< LOBPCG iteration cap (one exchange + one reduction each). > 0
  CertificatePreconditioner preconditioner = CertificatePreconditioner::kBlockJacobi;
  std::uint64_t seed = 1;  ///< Start vector (hash of the global pose ids and this seed).
  /// The exact interface test runs when the team's interface (poses with a cut measurement)
  /// has at most this many coordinates ((d+1) a pose): agent 0 factors a matrix that large,
  /// dense within each block's interface. 0 = LOBPCG only (an estimate, no proved bound). >= 0.
  /// Why 800: the Schur complements travel to agent 0 in one message step, 4 bytes a
  /// coordinate squared per block; at torus3D's 1,004 (N = 5) that is 4 MB and the certificate
  /// phase over DDS took 0.37-0.75 s against LOBPCG's 0.19-0.34 s, while sphere2500 (704) and
  /// city10000 (459 at N = 5, 768 at N = 10) decide in one certificate round
  /// (docs/distributed-certification.md).
  int interface_max_coordinates = 800;
  /// The interface test keeps one endpoint of each cut measurement (the one in the lower-
  /// numbered block) and eliminates the other inside its block: Sigma has about half the
  /// coordinates (torus3D, N = 5: 1,004 instead of 1,944), interface_max_coordinates counts
  /// those. false: every pose with a cut measurement is kept (both endpoints).
  bool interface_one_side = true;
  /// `certified` also needs the weak-duality bound (dual_bound.hpp) proved and within this
  /// relative tolerance: (f(Y) - f_lb) <= suboptimality_tolerance * max(1, |f(Y)|). >= 0.
  double suboptimality_tolerance = kDefaultSuboptimalityTolerance;
  /// Throws InputError naming the bad field.
  void validate() const;
};

/// Identical on every agent except `eigenvector`.
struct DistributedCertificateResult {
  /// With the interface test: the bound (below) proved and within suboptimality_tolerance (X
  /// is then within that relative distance of the optimum, dual_bound.hpp). Without it:
  /// LOBPCG converged to theta >= -eta and |grad f| <= suboptimality_tolerance max(1, |f|)
  /// (CertificateMethod::kLobpcg, an estimate).
  bool certified = false;
  /// The final Ritz value theta >= -eta (converged, or after an interface test that passed):
  /// an estimate, and alone it says nothing about optimality short of a critical point.
  bool psd_within_tolerance = false;
  /// The weak-duality bound at Y (dual_bound.hpp). Proved only by the interface test (its
  /// floor s0 from first_proof_shift and alpha from 1, both up by kProofShiftGrowth while the
  /// test fails, s0 to eta at most); without the test (interface above
  /// interface_max_coordinates, or a block too large to factor) nothing proves it:
  /// lower_bound is NaN and `certified` is LOBPCG's estimate at a critical point.
  DualBound bound;
  int proof_tests = 0;          ///< Interface tests run (each: a Schur step and a verdict step).
  bool converged = false;       ///< Ritz residual reached the tolerance.
  double min_eigenvalue = 0.0;  ///< Smallest Ritz value theta (>= lambda_min(S)).
  double residual = 0.0;        ///< ||S x - theta x|| at the end.
  double tolerance = 0.0;       ///< eta.
  double scale = 1.0;           ///< max(1, max diag Q).
  /// LOBPCG iterations (each: one exchange, one reduction), plus one for the interface test.
  int iterations = 0;
  bool interface_test = false;  ///< The exact interface test ran (its verdict decided).
  Eigen::MatrixXd eigenvector;  ///< 1 x (d+1)m: this agent's block of the unit Ritz vector.
};

/// Deterministic start-vector entry for coordinate c of global pose `pose` (in [-1, 1)).
double certificate_start_entry(std::uint64_t seed, std::size_t pose, int coordinate, int d);

struct BlockJacobi;

class CertificateProtocol : public AgentProcess {
 public:
  /// `state`: the agent at the point to certify (Y, and Yn = the neighbours' boundary poses
  /// of the same point). It must outlive the protocol and not change while it runs.
  CertificateProtocol(const AgentState& state, const BlockLayout& layout,
                      const DistributedCertificateOptions& options);
  ~CertificateProtocol() override;

  std::vector<OutgoingMessage> start() override;
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  const DistributedCertificateResult& result() const { return result_; }
  /// While it runs: LOBPCG iterations done and the current estimate of lambda_min (progress).
  std::uint32_t iteration() const { return iteration_; }
  double ritz_value() const { return theta_; }

 private:
  enum Step : std::uint32_t { kVector = 1, kReduce = 2, kSetup = 3, kSchur = 4, kVerdict = 5 };
  Eigen::MatrixXd apply(const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn);
  Eigen::MatrixXd gradient(const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn) const;
  void pump(std::vector<OutgoingMessage>& out);
  void send_boundary(const Eigen::MatrixXd& v, std::uint32_t round,
                     std::vector<OutgoingMessage>& out);
  void broadcast(std::uint32_t round, std::uint32_t step, const std::vector<double>& values,
                 std::vector<OutgoingMessage>& out);
  void begin_iteration(std::vector<OutgoingMessage>& out);
  void after_vector(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_reduce(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void finish(bool converged);
  void build_preconditioner();
  void start_lobpcg(std::vector<OutgoingMessage>& out);
  void after_setup(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_schur(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_verdict(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  std::vector<int> everyone() const;

  const AgentState& state_;
  const BlockLayout& layout_;
  DistributedCertificateOptions options_;
  // The agent's own problem, read only (the vectors' neighbour values are passed to each
  // product): a copy would be the block's largest transient (its Q_BB and edge data).
  const BlockProblem& problem_;
  SparseMatrix lambda_;  // Lambda_B on the block's coordinates
  // The same Lambda_B as d x d blocks (column-major), pose after pose: the LOBPCG products.
  std::vector<double> lambda_blocks_;
  void subtract_times_lambda(const Eigen::MatrixXd& v, Eigen::MatrixXd& out) const;
  std::unique_ptr<BlockJacobi> precon_;
  double local_max_diag_ = 0.0;
  MessageGate gate_;
  std::uint32_t iteration_ = 0;
  Eigen::MatrixXd x_, Sx_, w_, Sw_, p_, Sp_;
  double theta_ = 0.0, rr_local_ = 0.0;
  bool has_p_ = false;
  bool done_ = false;
  // The interface test: its verdict, and the Ritz pair on the iterate's row space.
  bool interface_certified_ = false;
  // The bound's parts (summed over the agents) and the interface test's current shift.
  double f_local_ = 0.0, trace_lambda_local_ = 0.0;
  double f_ = 0.0, trace_lambda_ = 0.0, gradient_norm_ = 0.0, poses_ = 0.0;
  double proof_shift_ = 0.0, proof_alpha_ = 1.0, proof_shift_cap_ = 0.0;
  // The ladder's floor (t = 1) and its largest certifying t (largest_certifying_multiplier).
  double proof_floor_ = 0.0, proof_largest_ = 0.0;
  double weight_sum_local_ = 0.0, weight_sum_ = 0.0;
  std::vector<double> weights_;  // proof_shift_weights of the agent's poses
  std::uint32_t proof_round_ = 0;
  void send_schur(std::vector<OutgoingMessage>& out);
  Eigen::VectorXd row_space_ritz_;  // coefficients over Y's rows
  double row_space_theta_ = 0.0, row_space_residual_ = 0.0;
  DistributedCertificateResult result_;
};

}  // namespace tessera
