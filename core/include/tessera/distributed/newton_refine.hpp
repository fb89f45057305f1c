#pragma once
// Distributed second-order refinement of a lifted iterate: Riemannian trust-region Newton steps
// on the WHOLE lifted problem, run by the agents together after the block-coordinate rounds.
//
// Why: block-coordinate descent reaches a gradient of 1e-2 in tens of rounds, but on long chains
// (parking-garage, ais2klinik) its slow modes leave the iterate 1e-4 relative above the optimum,
// and each further decade costs hundreds of rounds (docs/benchmarks/launch_phases.md). A Newton
// step solves for all modes at once; its truncated conjugate gradient (CG) needs only what the
// agents already exchange:
//   * Hessian-vector product: each agent forms its own block's rows of Hess f(X)[v] from its own
//     entries of v and its neighbours' public entries (one neighbour exchange per product);
//   * CG's inner products are all-agent sums in agent-id order (bit-identical on every agent);
//   * the preconditioner, where the team's interface is small (options.interface_max_coordinates),
//     is the Hessian's inverse by substructuring (distributed/interface_solve.hpp: each block's
//     factor and the interface's Schur complement, which agent 0 factors once per point and solves
//     with for every agent, NewtonRefineOptions::SigmaFactoring::kShipSolves), so a Newton step's
//     CG takes 1-3 iterations; elsewhere block Jacobi (AgentState::precondition: the tangent factor
//     of its block, else its Q_BB factor), optionally with a coarse correction over rigid motions
//     of smoothed pieces of the blocks (options.coarse, distributed/tangent_coarse_space.hpp):
//     block Jacobi alone moves information one block boundary per CG iteration.
// CG is in the Chronopoulos-Gear form (the two inner products of an iteration from one
// reduction, <p, Hp> by recurrence), so an iteration is one exchange then one reduction.
// The trust region (Steihaug-Toint truncated CG in the preconditioner's norm, ratio test on the
// true cost) keeps a step that leaves the quadratic model's region from raising the cost: the
// trial point's public poses are exchanged and its cost and gradient summed (one exchange and
// one reduction per step); an accepted trial is the next point with no further message. A
// rejected trial is retried along the same CG step at a quarter of its length (no new CG) before
// the region shrinks. The Hessian product is projected onto the tangent space (CG's residual must
// be tangent: the tangent preconditioner maps a normal part to zero). Trial points move each pose
// by the SE(d) exponential of its own twist (distributed/rigid_retraction.hpp): a Newton step on
// a long chain turns whole parts of the map, which the polar retraction with additive
// translations stretches (ais2klinik: f rose by 178 where the model predicted -0.047).
// One agent's state machine (messages in -> messages out, no transport), driven like
// RoundProtocol and CertificateProtocol, so in-process and DDS runs take identical iterates.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/distributed/newton_refine_options.hpp>
#include <tessera/distributed/newton_refine_result.hpp>
#include <tessera/problem/block_problem.hpp>
#include <utility>
#include <vector>

namespace tessera {

class TangentCoarseSpace;
class InterfaceSolve;
class PipelinedCg;
class CoarseHessianColumns;
class TranslationPreconditioner;
class TranslationInterfaceSolve;
class GaugeSpace;

/// Observer of a refinement's trial points (NewtonRefineProtocol::set_trial_observer): the own
/// block `Y` and the neighbours' public poses `Yn` there.
using TrialObserver = std::function<void(const Eigen::MatrixXd& Y, const Eigen::MatrixXd& Yn)>;

class NewtonRefineProtocol : public AgentProcess {
 public:
  /// Protocol steps (on the wire: the solve stage's phase base + these; RoundProtocol uses
  /// 0..5 in the same stage).
  enum Step : std::uint32_t {
    kStatus = 60,     ///< Cost share, ||g||^2 and active rows at the start point; the translation
                      ///< Schur complement (exact trial translations).
    kDirection = 61,  ///< Public entries of the preconditioned residual z.
    kSums = 62,       ///< CG's <r, z>, <z, H z>, <r, r>.
    kTrial = 63,      ///< Public poses of the trial point.
    kTrialSums = 64,  ///< Cost share and ||g||^2 at the trial point.
    kCoarse = 65,     ///< The coarse matrix's share and Phi^T g at the current point.
    kTranslationDirection = 66,  ///< Trial translations: public entries of the CG's z.
    kTranslationSums = 67,       ///< Trial translations: <r, z>, <z, H z>.
    kInterface = 68,             ///< Interface solves: each block's Schur complement and couplings.
    kTranslationSolve = 69,      ///< Exact trial translations: each block's interface residual.
    kSolution =
        70,  ///< kShipSolves: Sigma's solve, each agent's segment, from the agent holding it.
    kTranslationSolution = 71  ///< Exact trial translations with one factor of their Sigma
                               ///< (translation_one_factor_min_poses): the holder's u.
  };
  /// The last of the steps: [kStatus, kLastStep] are the refinement's.
  static constexpr std::uint32_t kLastStep = kTranslationSolution;
  static bool is_refine_step(std::uint32_t step) { return step >= kStatus && step <= kLastStep; }

  /// `state`: the agent at the point to refine (Y, and Yn = the neighbours' public poses of the
  /// same point). It must outlive the protocol; on done() its sequences are reset to the final
  /// point (AgentState::reset_iterate).
  NewtonRefineProtocol(AgentState& state, const BlockLayout& layout,
                       const NewtonRefineOptions& options);
  ~NewtonRefineProtocol() override;

  std::vector<OutgoingMessage> start() override;
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  std::size_t messages_needed() const override;
  /// The current message step's missing senders (a stalled run names them).
  std::optional<AwaitedMessages> awaited() const override;
  const NewtonRefineResult& result() const { return result_; }
  /// Called with each trial point, its translations solved, as the trial's sums go out: the own
  /// block at the iterate's rank (rows no agent uses are zero), exactly the block the agent
  /// holds if the trial is accepted, and its neighbours' public poses there (problem().neighbors()
  /// order, the same rows), the bits each neighbour holds of its own. A caller that must exchange
  /// the accepted point's poses, or values computed from them, can send them beside the sums
  /// instead of in a message step of its own (robust GNC's weighted solves).
  void set_trial_observer(TrialObserver observer) { trial_observer_ = std::move(observer); }
  /// Before start(): ||grad f|| at the start point as the team last summed it (the rounds' last
  /// status; the same on every agent). At or below grad_norm_tol the refinement will stop at
  /// its start's sum, so the interface shares (interface_in_status) stay out of that sum: a
  /// robust run's final solve that only checks its gradient sent them for nothing (CSAIL, 25 %
  /// random outliers: 1.4 MB). Only bytes and work depend on it, never the iterates.
  void set_start_grad_norm(double grad_norm) { start_grad_norm_ = grad_norm; }

  /// Where the refinement is, for progress reports: the trust-region step being computed
  /// (1-based, rejected ones and backtracks counted), the CG iterations of that step so far and
  /// ||grad f|| at the current point. nullopt until the start point's sums are in.
  struct Progress {
    std::uint32_t step = 0, cg_iteration = 0;
    double grad_norm = 0.0;
  };
  std::optional<Progress> progress() const {
    if (message_round_ == 0) return std::nullopt;
    return Progress{static_cast<std::uint32_t>(result_.steps + 1),
                    static_cast<std::uint32_t>(step_.cg_iterations), gnorm_};
  }

 private:
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  void pump(std::vector<OutgoingMessage>& out);
  void send_public(const Eigen::MatrixXd& v, std::uint32_t step, std::vector<OutgoingMessage>& out);
  void broadcast(std::uint32_t step, const std::vector<double>& values,
                 std::vector<OutgoingMessage>& out);
  // The neighbours' public entries of a vector sent in one step, into vn (zero elsewhere).
  void neighbours_into(const MessageGate::Inbox& inbox, Eigen::MatrixXd& vn) const;
  // Local pieces at (X_, Xn_): egrad_, g_ and the cost share.
  double evaluate_point();
  Eigen::MatrixXd hessian(const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn);
  // The same at another point X (egrad its Euclidean gradient).
  Eigen::MatrixXd hessian_at(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad,
                             const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn);
  void after_status(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Whether this agent's rows in use (own and neighbour poses) are all below d.
  bool nonzero_rows_within(Eigen::Index d) const;
  // The point and its gradients on rows_ only (rows_taken_).
  void take_rows();
  void begin_cg(std::vector<OutgoingMessage>& out);
  // The coarse matrix's share at the current point, summed by every agent (kCoarse).
  void send_coarse(std::vector<OutgoingMessage>& out);
  void after_coarse(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Interface solves: this block's factor and share of Sigma at the current point (kInterface),
  // then every agent's Sigma.
  void send_interface(std::vector<OutgoingMessage>& out);
  void after_interface(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // send_interface()'s message values: this block's factor and share of Sigma at the current
  // point, its interface residuals and the gauge's sums (sets the point's gauge and forward
  // solves of -g).
  std::vector<double> interface_share(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                      const Eigen::MatrixXd& egrad, const Eigen::MatrixXd& g,
                                      bool pending);
  // The point's gauge and forward solves (gauge_, gauge_hv_, iy_g_, gauge_fv_, gauge_fhv_)
  // swapped with the trial point's (interface_in_trial_sums).
  void swap_point_parts();
  // The accepted trial's interface shares, carried by its sum: the step kInterface would be.
  void use_carried_shares(std::vector<OutgoingMessage>& out);
  // Whether this trial's sum carries the whole interface share at the trial point
  // (interface_in_trial_sums): the same inputs, so the same answer, on every agent.
  bool ship_trial_interface() const;
  // kShipSolves: what of a share the agents other than the holder receive.
  std::vector<double> brief_share(const std::vector<double>& values) const;
  // kShipSolves: `full` to the holder (and this agent's own gate), `brief` to the others.
  void send_to_holder(std::uint32_t step, const std::vector<double>& full,
                      const std::vector<double>& brief, std::vector<OutgoingMessage>& out);
  // after_interface() on the team's shares (every agent's, in id order), wherever they came in.
  void use_interface_shares(const std::vector<std::pair<int, const std::vector<double>*>>& shares,
                            std::vector<OutgoingMessage>& out);
  // The interface solves where they apply to the team's interface (its size within the cap),
  // null elsewhere; the layout is the same on every agent, so is the answer.
  std::unique_ptr<InterfaceSolve> make_interface();
  // v's columns of the interface solve's grounded pose set to zero (where this block has it).
  void ground_pose(Eigen::MatrixXd& v) const;
  // The gauge's numbers in each interface share: V^T V, V^T H V (k x k each) and V^T g.
  std::size_t gauge_share_size() const;
  // The CG step's part orthogonal to the gauge, with its model's <g, s> and <s, H s>.
  void project_step_off_gauge();
  // Projecting the gauge: z, H z (and H z's interface residuals) of this iteration projected
  // off V, and the iteration's sums t (as after_sums reads them) corrected to theirs.
  void project_iteration_off_gauge(std::vector<double>& t);
  // CG from s = 0 at the current point (the coarse matrix, if any, is current).
  void start_cg(std::vector<OutgoingMessage>& out);
  // x's entries at the coarse unknowns this agent touches (coarse_hphi_'s columns).
  Eigen::VectorXd touched_of(const Eigen::VectorXd& x) const;
  // The block preconditioner for the next CG solve (options_.refactor_every_step).
  void prepare_preconditioner();
  void send_direction(std::vector<OutgoingMessage>& out);
  // kShipSolves: a share's trailing interface residuals (this block's), in values.
  std::size_t share_tail() const;
  // kShipSolves, on the holder: u = Sigma^-1 rhat of the current residual, each agent's segment
  // sent to it (kSolution, after the flag and grounding); everyone waits for it. With ok false
  // (no positive definite Sigma at this point), the flag 0 alone.
  void send_solution(bool ok, std::vector<OutgoingMessage>& out);
  void after_solution(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // After a point's Sigma: whether the CG uses it (ok), the gauge's sums, fallback otherwise.
  void take_interface_verdict(bool ok);
  // start_cg()'s state (s = 0, r = -g, the interface residuals) without the first direction.
  void reset_cg();
  void after_direction(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void try_step(const std::string& cg_stop, std::vector<OutgoingMessage>& out);
  void after_trial(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_trial_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void finish(const std::string& why);
  // The trial point's translations re-solved for its rotations (translation_iterations).
  void start_translations(std::vector<OutgoingMessage>& out);
  void send_translation_direction(std::vector<OutgoingMessage>& out);
  void after_translation_direction(const MessageGate::Inbox& inbox,
                                   std::vector<OutgoingMessage>& out);
  void after_translation_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Exact trial translations: the team's interface solve, then the trial's sums.
  void after_translation_solve(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // One translation Sigma factor: the holder's u (flag first) taken by every agent.
  void after_translation_solution(const MessageGate::Inbox& inbox,
                                  std::vector<OutgoingMessage>& out);
  // The trial's translations from u (the team's interface rows), then the trial's sums.
  void take_translation_solution(const Eigen::MatrixXd& u, std::vector<OutgoingMessage>& out);
  // The trial point's cost share and ||g||^2 (kTrialSums), its neighbours' poses set; with
  // ship_trial_shares(), the block's share of Sigma at the trial point after them.
  void send_trial_sums(std::vector<OutgoingMessage>& out);
  // Whether this trial's sum carries the Sigma shares (kShipFactor): the same inputs,
  // so the same answer, on every agent.
  bool ship_trial_shares() const;
  // Agent 0 with the shares in hand: Sigma assembled and factored, its factor's message values.
  std::vector<double> factor_shipped_sigma();

  // Charges this thread's CPU time since the last switch to the current part, then makes
  // `part` (a field of result_.times, or nullptr between messages) the current one.
  void charge_to(double* part);

  AgentState& state_;
  const BlockLayout& layout_;
  NewtonRefineOptions options_;
  BlockProblem problem_;  // own copy: its neighbour poses are set to directions
  MessageGate gate_;
  double* timed_part_ = nullptr;  // charge_to()'s current part and its start (thread CPU s)
  double timed_since_ = 0.0;
  double wall_start_ = 0.0;          // steady clock at start(), s
  std::uint32_t message_round_ = 0;  // one per message step, the same on every agent
  std::vector<int> everyone_;        // the agents every reduction waits for: 0 .. N-1
  std::vector<Eigen::Index> rows_;   // active rows (non-zero on some agent)
  // The point and its local pieces; the trial point.
  Eigen::MatrixXd X_, Xn_, egrad_, g_, Xt_, Xtn_, egrad_t_, g_t_;
  double f_ = 0.0, gnorm_ = 0.0;
  // CG on H s = -g: s, r, z = P r, w = H z, p, q = H p.
  Eigen::MatrixXd s_, r_, z_, w_, p_, q_;
  Eigen::MatrixXd zn_;  // the neighbours' z, kept between CG steps for its storage
  // Its scalars (iterations, the previous gamma and alpha, the preconditioned norms of s, p).
  std::unique_ptr<PipelinedCg> cg_;
  double model_ = 0.0;           // m(s) = <g, s> + <s, H s> / 2
  double gs_ = 0.0, sHs_ = 0.0;  // <g, s>, <s, H s> of the CG step
  Eigen::MatrixXd s_full_;       // the CG step; a backtrack tries scale_ of it
  double scale_ = 1.0;
  int backtracks_ = 0;
  double cg_target_ = 0.0;     // residual norm that ends the CG
  double radius_ = 0.0;        // 0 = unbounded
  bool refactor_due_ = false;  // a step was accepted since the last factorization
  // Coarse correction (options_.coarse): the space at the active rows, the pseudo-inverse of
  // its Galerkin matrix, Phi^T g at the current point, Phi^T r and Phi^T q of the CG
  // (recurrences, as r and q: Phi^T w rides in each iteration's sum).
  std::unique_ptr<TangentCoarseSpace> coarse_;
  // Balancing: the own rows of H Phi, one column per touched unknown, on its non-zero poses.
  std::unique_ptr<CoarseHessianColumns> coarse_hphi_;
  Eigen::VectorXd coarse_hy_;  // balancing: this agent's share of (H Phi)^T y
  Eigen::VectorXd coarse_g_, coarse_r_, coarse_q_;
  bool coarse_due_ = true;  // the point changed since the coarse matrix was summed
  // Kept coarse matrix: accepted steps since it was summed, and whether this CG balances
  // (only with the matrix summed at its own point: balancing needs that point's H Phi).
  int coarse_kept_steps_ = 0;
  bool coarse_fresh_ = true;
  // Whether the current trial's sum carries Phi^T g at the trial point (an accepted one keeps
  // the matrix): that step then sends no coarse sum.
  bool trial_coarse_g_ = false;
  bool ship_trial_coarse_gradient() const;
  bool balancing() const { return options_.coarse_balancing && coarse_fresh_; }
  // Interface solves (options_.interface_max_coordinates): the solver, whether Sigma is due
  // (the point changed) and whether this point's CG uses it; y = L^-1 J^T of r, q, w and of -g
  // (the block's forward solves) and the team's interface residuals of r, q and -g, carried by
  // CG's recurrences (the one of H z rides in the iteration's sum).
  std::unique_ptr<InterfaceSolve> interface_;
  bool interface_due_ = true, use_interface_ = false;
  // options_.interface_in_status: the start's sum has the interface shares' field (the same on
  // every agent); this agent's point is on the first d rows already (its share computed there).
  bool status_shares_ = false, rows_taken_ = false;
  // interface_in_trial_sums: whether the current trial's sum carries its interface shares, and
  // whether the accepted trial's (next_shares_) are in hand for the next CG; the trial point's
  // gauge and forward solves meanwhile (swap_point_parts()).
  bool trial_interface_ = false, interface_carried_ = false;
  std::unique_ptr<GaugeSpace> trial_gauge_;
  std::vector<Eigen::MatrixXd> trial_gauge_hv_;
  Eigen::VectorXd trial_iy_g_;
  Eigen::MatrixXd trial_gauge_fv_, trial_gauge_fhv_;
  double start_grad_norm_ = std::numeric_limits<double>::quiet_NaN();  // NaN: not known
  // kShipFactor: whether the current trial's sum carries the shares; the team's shares at the
  // accepted trial (id order), in hand for the next interface step (shares_ready_).
  bool trial_shares_ = false, shares_ready_ = false;
  std::vector<std::vector<double>> next_shares_;
  // kShipSolves: the point's Sigma verdict is the holder's, not yet known here (it comes with
  // the point's first solution).
  bool verdict_due_ = false;
  // The agent that assembles and factors Sigma for the team (kShipFactor, kShipSolves): always
  // the same one, so its pattern and symbolic analysis are laid out once.
  static constexpr int kSigmaHolder = 0;
  Eigen::VectorXd iy_r_, iy_q_, iy_w_, iy_g_, ir_, iq_, ir_g_;
  // The gauge with the interface solves (distributed/gauge_space.hpp): its basis V and H V at
  // the point, the sums V^T V, V^T H V and V^T g (in the interface matrix's sum), and the
  // CG's V^T p, V^T H p, V^T s, V^T H s by recurrence (V^T z, V^T H z ride in its sums).
  std::unique_ptr<GaugeSpace> gauge_;
  std::vector<Eigen::MatrixXd> gauge_hv_;
  Eigen::MatrixXd gauge_vv_, gauge_vhv_;
  Eigen::VectorXd gauge_vg_, gauge_vp_, gauge_vhp_, gauge_vs_, gauge_vhs_;
  bool use_gauge_ = false;
  // options_.project_gauge at this point (with use_gauge_): the forward solves F(V), F(H V)
  // (own, one column each), the team's interface residuals R(V), R(H V) (team_size x k) and
  // (H V)^T (H V); the projection's coefficients a (of z) and b (of H z) per iteration.
  bool project_gauge_ = false;
  Eigen::MatrixXd gauge_fv_, gauge_fhv_, gauge_rv_, gauge_rhv_, gauge_hvhv_;
  // Translation solve at the trial point: the own block's translation Laplacian factor, CG
  // state (x the translation change, in the pose layout with zero rotation columns).
  std::unique_ptr<TranslationPreconditioner> translation_preconditioner_;
  bool translations_solved_ = false;  // the current trial's translations are re-solved
  Eigen::MatrixXd tx_, tr_, tz_, tzn_, tw_, tp_, tq_;
  std::unique_ptr<PipelinedCg> tcg_;
  // Exact trial translations (options_.translation_interface_max_poses): the solve (in use once
  // ready()) and the forward solve of the current trial's right-hand side.
  std::unique_ptr<TranslationInterfaceSolve> translation_solve_;
  Eigen::MatrixXd ty_;
  // Only kSigmaHolder factors the translation Sigma (options_.translation_one_factor_min_poses;
  // decided from the layout, the same on every agent): the others send it their residuals and
  // take its u (kTranslationSolution).
  bool translation_one_factor_ = false;
  NewtonRefineStep step_;
  TrialObserver trial_observer_;
  bool done_ = false;
  NewtonRefineResult result_;
};

}  // namespace tessera
