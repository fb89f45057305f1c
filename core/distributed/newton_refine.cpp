#include <time.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/problem/pose_kernels.hpp>
#include <tessera/util/input_error.hpp>

#include "distributed/coarse_hessian_columns.hpp"
#include "distributed/gauge_space.hpp"
#include "distributed/interface_solve.hpp"
#include "distributed/nonzero_rows.hpp"
#include "distributed/pipelined_cg.hpp"
#include "distributed/public_pose_messages.hpp"
#include "distributed/rigid_retraction.hpp"
#include "distributed/tangent_coarse_space.hpp"
#include "distributed/translation_interface_solve.hpp"
#include "distributed/translation_preconditioner.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera {

namespace {

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// 1 for each row of X or Y that is non-zero somewhere, 0 for the others: summed over the agents,
// the rows in use anywhere.
std::vector<double> row_indicators(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y) {
  std::vector<double> used(static_cast<std::size_t>(X.rows()), 0.0);
  for (Eigen::Index k : nonzero_rows(X, Y)) used[static_cast<std::size_t>(k)] = 1.0;
  return used;
}

}  // namespace

NewtonRefineProtocol::NewtonRefineProtocol(AgentState& state, const BlockLayout& layout,
                                           const NewtonRefineOptions& options)
    : state_(state),
      layout_(layout),
      options_(options),
      problem_(state.problem()),
      cg_(std::make_unique<PipelinedCg>()),
      tcg_(std::make_unique<PipelinedCg>()) {
  options_.validate();
  everyone_.resize(static_cast<std::size_t>(layout_.num_blocks));
  for (int b = 0; b < layout_.num_blocks; ++b) everyone_[static_cast<std::size_t>(b)] = b;
}

NewtonRefineProtocol::~NewtonRefineProtocol() = default;

int message_steps(const std::vector<NewtonRefineResult>& refines) {
  int steps = 0;
  for (const NewtonRefineResult& r : refines) steps += r.message_steps();
  return steps;
}

void NewtonRefineProtocol::charge_to(double* part) {
  // The same part goes on: its time is charged at the next switch. Each reading of the thread's
  // CPU clock is a system call (no vDSO path for it), and a CG iteration of block Jacobi delivers
  // each agent one message per neighbour and one per agent.
  if (part == timed_part_) return;
  const double now = thread_cpu_s();
  if (timed_part_) {
    *timed_part_ += now - timed_since_;
    result_.times.cpu_s += now - timed_since_;
  }
  timed_part_ = part;
  timed_since_ = now;
}

void NewtonRefineProtocol::send_public(const Eigen::MatrixXd& v, std::uint32_t step,
                                       std::vector<OutgoingMessage>& out) {
  const auto& adj = layout_.adjacent[static_cast<std::size_t>(state_.id())];
  send_public_poses(state_, v, BlockKind::kY, adj, message_round_, step, out);
  gate_.expect(message_round_, step, adj);
  ++result_.exchanges;
}

void NewtonRefineProtocol::broadcast(std::uint32_t step, const std::vector<double>& values,
                                     std::vector<OutgoingMessage>& out) {
  PoseBlockMessage m = make_reduction_message(state_.id(), message_round_, step, values);
  gate_.add(state_.id(), message_round_, step, m);  // our own share joins like any other
  OutgoingMessage o;
  o.message = std::move(m);
  o.broadcast = true;
  out.push_back(std::move(o));
  gate_.expect(message_round_, step, everyone_);
  ++result_.reductions;
}

void NewtonRefineProtocol::neighbours_into(const MessageGate::Inbox& inbox,
                                           Eigen::MatrixXd& vn) const {
  // setZero(rows, cols) keeps the storage of a buffer that has the size already (every CG step).
  vn.setZero(static_cast<Eigen::Index>(rows_.size()),
             (problem_.dim() + 1) * static_cast<Eigen::Index>(problem_.num_neighbors()));
  for (const auto& [sender, m] : inbox) state_.absorb(std::get<PoseBlockMessage>(m), vn);
}

double NewtonRefineProtocol::evaluate_point() {
  if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(Xn_);
  double share = 0.0;
  problem_.cost(X_, &share);
  egrad_ = problem_.euclidean_gradient(X_);
  g_ = problem_.riemannian_gradient(X_, egrad_);
  return share;
}

Eigen::MatrixXd NewtonRefineProtocol::hessian(const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn) {
  return hessian_at(X_, egrad_, v, vn);
}

Eigen::MatrixXd NewtonRefineProtocol::hessian_at(const Eigen::MatrixXd& X,
                                                 const Eigen::MatrixXd& egrad,
                                                 const Eigen::MatrixXd& v,
                                                 const Eigen::MatrixXd& vn) {
  // The block's rows of Hess f(X)[v]: 2 (v_B Q_BB + v_N Q_NB) (euclidean_gradient with the
  // neighbours set to v_N), projected with the Weingarten term of the block's own poses.
  if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(vn);
  Eigen::MatrixXd H = problem_.euclidean_gradient(v);
  apply_hessian_projection(X, egrad, v, problem_.dim(), H);
  // The kernel leaves the Weingarten term V sym(X^T egrad) unprojected (its normal part does
  // not change an inner product with a tangent vector). CG's residual must be tangent: the
  // tangent preconditioner maps a normal component to zero, so <r, P r> fell to 1e-34 while
  // ||r|| stayed at half its start (sphere2500) and the residual test never held.
  return problem_.manifold(static_cast<int>(X.rows())).tangent_project(X, H);
}

std::vector<OutgoingMessage> NewtonRefineProtocol::start() {
  std::vector<OutgoingMessage> out;
  wall_start_ = steady_s();
  charge_to(&result_.times.setup_s);
  // Local active rows first; the reduction makes them the same everywhere.
  rows_.clear();
  for (Eigen::Index k = 0; k < state_.Y.rows(); ++k) rows_.push_back(k);
  X_ = state_.Y;
  Xn_ = state_.Yn;
  const double share = evaluate_point();
  std::vector<double> values{share, g_.squaredNorm()};
  const std::vector<double> used = row_indicators(state_.Y, state_.Yn);
  values.insert(values.end(), used.begin(), used.end());
  // Exact trial translations: L_BB's factor and Schur complement do not depend on the point, so
  // they ride in this first sum.
  std::vector<double> translation_share;
  if (options_.translation_iterations > 0 && options_.translation_interface_max_poses > 0 &&
      layout_.num_blocks > 1) {
    const Eigen::Index team = interface_pose_count(layout_);
    if (team > 0 && team <= options_.translation_interface_max_poses) {
      translation_solve_ =
          std::make_unique<TranslationInterfaceSolve>(problem_, layout_, state_.id());
      translation_share = translation_solve_->share();
      translation_one_factor_ = team >= options_.translation_one_factor_min_poses;
    }
  }
  // The interface shares at the start point, in this sum too: the count of this block's, then
  // its values (0: none; after_status() then sends them in a step of their own).
  // Not where the team's last sum at this point says the refinement stops at this one.
  status_shares_ =
      options_.interface_in_status && options_.coarse == NewtonRefineOptions::Coarse::kNone &&
      state_.Y.rows() >= problem_.dim() && !(start_grad_norm_ <= options_.grad_norm_tol);
  if (status_shares_) interface_ = make_interface();
  status_shares_ = status_shares_ && interface_;
  std::vector<double> full, brief;
  if (status_shares_ && nonzero_rows_within(problem_.dim())) {
    // Each share is at the point on the first d rows, the interface solves' rank: the ones in
    // use on every agent unless some agent says otherwise (after_status()).
    rows_.resize(static_cast<std::size_t>(problem_.dim()));
    take_rows();
    full = interface_share(X_, Xn_, egrad_, g_, false);
    if (options_.sigma_factoring == SigmaFactoring::kShipSolves) brief = brief_share(full);
    charge_to(&result_.times.setup_s);
  }
  const auto with_shares = [&](const std::vector<double>& shares) {
    std::vector<double> v = values;
    if (status_shares_) {
      v.push_back(static_cast<double>(shares.size()));
      v.insert(v.end(), shares.begin(), shares.end());
    }
    v.insert(v.end(), translation_share.begin(), translation_share.end());
    return v;
  };
  if (status_shares_ && options_.sigma_factoring == SigmaFactoring::kShipSolves)
    send_to_holder(kStatus, with_shares(full), with_shares(full.empty() ? full : brief), out);
  else
    broadcast(kStatus, with_shares(full), out);
  pump(out);
  charge_to(nullptr);
  return out;
}

bool NewtonRefineProtocol::nonzero_rows_within(Eigen::Index d) const {
  for (Eigen::Index k : nonzero_rows(state_.Y, state_.Yn))
    if (k >= d) return false;
  return true;
}

void NewtonRefineProtocol::take_rows() {
  // Every step maps rows that are zero on every agent to zero: work on the others only.
  X_ = state_.Y(rows_, Eigen::all);
  Xn_ = state_.Yn(rows_, Eigen::all);
  egrad_ = egrad_(rows_, Eigen::all).eval();
  g_ = g_(rows_, Eigen::all).eval();
  rows_taken_ = true;
}

std::unique_ptr<InterfaceSolve> NewtonRefineProtocol::make_interface() {
  if (options_.interface_max_coordinates <= 0 || layout_.num_blocks <= 1) return nullptr;
  auto solve = std::make_unique<InterfaceSolve>(problem_, layout_, state_.id(), options_.analyses);
  if (solve->team_size() <= 0 || solve->team_size() > options_.interface_max_coordinates)
    return nullptr;
  if (options_.sigma_factoring == SigmaFactoring::kShipSolves &&
      solve->team_size() < options_.ship_solves_min_coordinates)
    options_.sigma_factoring = SigmaFactoring::kEveryAgent;
  return solve;
}

std::vector<OutgoingMessage> NewtonRefineProtocol::handle(const ProtocolMessage& message) {
  const std::uint32_t sender = message_sender(message);
  const std::uint32_t step = message_phase(message);
  if (sender >= static_cast<std::uint32_t>(layout_.num_blocks) || !is_refine_step(step))
    throw std::runtime_error("newton refine: agent " + std::to_string(state_.id()) +
                             ": malformed message (sender " + std::to_string(sender) + ", step " +
                             std::to_string(step) + ")");
  if (!gate_.add(static_cast<int>(sender), message_round(message), step, message))
    throw std::runtime_error("newton refine: agent " + std::to_string(state_.id()) +
                             ": duplicate message from agent " + std::to_string(sender));
  std::vector<OutgoingMessage> out;
  pump(out);
  charge_to(nullptr);
  return out;
}

std::size_t NewtonRefineProtocol::messages_needed() const {
  if (done_) return 0;
  return std::max<std::size_t>(gate_.missing().size(), 1);
}

std::optional<AwaitedMessages> NewtonRefineProtocol::awaited() const {
  if (done_) return std::nullopt;
  AwaitedMessages a;
  a.round = gate_.round();
  a.phase = gate_.step();
  for (int s : gate_.missing()) a.senders.push_back(static_cast<std::uint32_t>(s));
  if (a.senders.empty()) return std::nullopt;  // not after pump(); never a wait for nothing
  return a;
}

void NewtonRefineProtocol::pump(std::vector<OutgoingMessage>& out) {
  while (!done_) {
    std::optional<MessageGate::Inbox> ready = gate_.take_ready();
    if (!ready) return;              // a message that completes no step is stored, not timed
    charge_to(&result_.times.cg_s);  // until the step's handler names its part
    const std::uint32_t step = gate_.step();
    ++message_round_;
    switch (step) {
      case kStatus:
        after_status(*ready, out);
        break;
      case kDirection:
        after_direction(*ready, out);
        break;
      case kSums:
        after_sums(*ready, out);
        break;
      case kTrial:
        after_trial(*ready, out);
        break;
      case kCoarse:
        after_coarse(*ready, out);
        break;
      case kTranslationDirection:
        after_translation_direction(*ready, out);
        break;
      case kTranslationSums:
        after_translation_sums(*ready, out);
        break;
      case kInterface:
        after_interface(*ready, out);
        break;
      case kTranslationSolve:
        after_translation_solve(*ready, out);
        break;
      case kSolution:
        after_solution(*ready, out);
        break;
      case kTranslationSolution:
        after_translation_solution(*ready, out);
        break;
      default:
        after_trial_sums(*ready, out);
        break;
    }
  }
}

void NewtonRefineProtocol::after_status(const MessageGate::Inbox& inbox,
                                        std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.setup_s);
  const std::size_t r = static_cast<std::size_t>(state_.Y.rows());
  // The sums (in id order, as reduce_in_id_order), then (status_shares_) each block's
  // interface share after its count, then each block's translation share.
  std::vector<double> t(2 + r, 0.0);
  std::vector<std::vector<double>> shares;
  std::vector<std::vector<double>> interface_shares;  // every block's, or none
  for (const auto& [sender, m] : inbox) {
    const auto* p = std::get_if<PoseBlockMessage>(&m);
    std::size_t at = 2 + r;
    std::size_t count = 0;
    if (p && status_shares_ && p->data.size() > at) {
      count = static_cast<std::size_t>(p->data[at]);
      ++at;
    }
    if (!p || p->data.size() < at + count ||
        (p->data.size() > at + count) != (translation_solve_ != nullptr) ||
        (status_shares_ && at == 2 + r))
      throw std::runtime_error("newton refine: malformed status from agent " +
                               std::to_string(sender));
    for (std::size_t k = 0; k < 2 + r; ++k) t[k] += p->data[k];
    const auto from = p->data.begin() + static_cast<std::ptrdiff_t>(at);
    if (count > 0 && interface_shares.size() == static_cast<std::size_t>(sender))
      interface_shares.emplace_back(from, from + static_cast<std::ptrdiff_t>(count));
    if (translation_solve_)
      shares.emplace_back(from + static_cast<std::ptrdiff_t>(count), p->data.end());
  }
  if (translation_solve_) {
    std::vector<const std::vector<double>*> ptrs;
    for (const auto& v : shares) ptrs.push_back(&v);
    // With one factor the others only check the shares; a factor that fails on the holder is
    // announced with its first u (after_translation_solution()), else it fails on every agent.
    const bool factor = !translation_one_factor_ || state_.id() == kSigmaHolder;
    if (translation_solve_->assemble(ptrs, factor) ||
        (factor && translation_one_factor_ && translation_solve_->assemble(ptrs, false)))
      result_.translation_interface_poses = static_cast<int>(translation_solve_->team_size());
    else
      translation_solve_.reset();  // a block's L_BB is singular: the CG below
  }
  std::vector<Eigen::Index> active;
  for (std::size_t k = 0; k < r; ++k)
    if (t[2 + k] > 0) active.push_back(static_cast<Eigen::Index>(k));
  if (active.empty()) active.push_back(0);
  // The shares are at the first d rows: usable where those are the team's rows in use and
  // every block sent its share.
  bool shares_usable = interface_shares.size() == static_cast<std::size_t>(layout_.num_blocks) &&
                       active.size() == static_cast<std::size_t>(problem_.dim());
  for (std::size_t k = 0; shares_usable && k < active.size(); ++k)
    shares_usable = active[k] == static_cast<Eigen::Index>(k);
  if (rows_taken_ && !shares_usable) {
    X_ = state_.Y;  // back to the whole start point
    Xn_ = state_.Yn;
    evaluate_point();
    rows_taken_ = false;
  }
  rows_ = active;
  if (!rows_taken_) take_rows();
  f_ = t[0];
  gnorm_ = std::sqrt(std::max(0.0, t[1]));
  result_.initial_cost = result_.cost = f_;
  result_.initial_grad_norm = result_.grad_norm = gnorm_;
  radius_ = options_.initial_radius;
  if (gnorm_ <= options_.grad_norm_tol) {
    interface_.reset();  // a share sent in the start's sum is not used
    return finish("grad_norm");
  }
  if (options_.coarse != NewtonRefineOptions::Coarse::kNone) {
    const CoarseSpace* space =
        options_.coarse == NewtonRefineOptions::Coarse::kSmoothed ? state_.refine_space() : nullptr;
    coarse_ = std::make_unique<TangentCoarseSpace>(
        space, layout_, problem_.owned(), problem_.neighbors(), problem_.dim(),
        static_cast<int>(rows_.size()), options_.coarse_min_blocks);
    // Every piece alone in its group (robots that have not met): the correction is zero, so no
    // coarse matrix is summed (the layout is the same on every agent, so is the decision).
    if (!coarse_->linked()) coarse_.reset();
    result_.coarse_unknowns = coarse_ ? coarse_->size() : 0;
  }
  // Interface solves: at rank d (tangent coordinates) without a coarse correction, where the
  // team's interface fits. The layout is the same on every agent, so is the decision.
  if (!coarse_ && static_cast<int>(rows_.size()) == problem_.dim()) {
    if (!interface_) interface_ = make_interface();
  } else {
    interface_.reset();
  }
  if (interface_) {
    result_.interface_coordinates = static_cast<int>(interface_->team_size());
    refactor_due_ = true;  // block Jacobi's factor only where a point falls back to it
  } else {
    prepare_preconditioner();
  }
  if (options_.translation_iterations > 0 && !translation_solve_)
    translation_preconditioner_ = std::make_unique<TranslationPreconditioner>(problem_);
  if (interface_ && shares_usable) {
    std::vector<std::pair<int, const std::vector<double>*>> in;
    for (std::size_t b = 0; b < interface_shares.size(); ++b)
      in.emplace_back(static_cast<int>(b), &interface_shares[b]);
    return use_interface_shares(in, out);
  }
  begin_cg(out);
}

void NewtonRefineProtocol::prepare_preconditioner() {
  charge_to(&result_.times.factor_s);
  if (options_.refactor_every_step && options_.hessian_multipliers)
    state_.refresh_tangent(X_, egrad_);
  else if (options_.refactor_every_step)
    state_.refresh_tangent(X_);
  else {
    // The start's CG ran on the grown factor; the first accepted point builds the deferred one.
    if (options_.refactor_grown_factors && result_.accepted_steps > 0)
      state_.rebuild_grown_tangent(X_);
    state_.ensure_tangent(X_);
  }
  refactor_due_ = false;
}

void NewtonRefineProtocol::begin_cg(std::vector<OutgoingMessage>& out) {
  // Only before a CG that will run: the factor at the point where the refinement stops would
  // not be used.
  if (interface_ && interface_due_)
    return interface_carried_ ? use_carried_shares(out) : send_interface(out);
  if (refactor_due_ && !use_interface_) prepare_preconditioner();
  if (coarse_ && coarse_due_) return send_coarse(out);
  start_cg(out);
}

Eigen::VectorXd NewtonRefineProtocol::touched_of(const Eigen::VectorXd& x) const {
  const std::vector<int>& touched = coarse_->touched();
  Eigen::VectorXd out(static_cast<Eigen::Index>(touched.size()));
  for (std::size_t c = 0; c < touched.size(); ++c)
    out(static_cast<Eigen::Index>(c)) = x(touched[c]);
  return out;
}

void NewtonRefineProtocol::start_cg(std::vector<OutgoingMessage>& out) {
  reset_cg();
  send_direction(out);
}

void NewtonRefineProtocol::reset_cg() {
  charge_to(&result_.times.cg_s);
  step_ = NewtonRefineStep{};
  step_.radius = radius_;
  cg_->restart();
  s_ = Eigen::MatrixXd::Zero(X_.rows(), X_.cols());
  r_ = -g_;
  if (coarse_) coarse_r_ = -coarse_g_;
  if (use_interface_) {
    iy_r_ = iy_g_;
    ir_ = ir_g_;
    gauge_vs_ = gauge_vhs_ = Eigen::VectorXd::Zero(gauge_->size());
    if (project_gauge_) {
      // r = -P g = -g + V c with c = (V^T V)^-1 V^T g (round-off: f is invariant along V), and
      // its interface residuals from those of V.
      const Eigen::VectorXd c = gauge_vv_.llt().solve(gauge_vg_);
      gauge_->subtract(-c, r_);
      iy_r_ += gauge_fv_ * c;
      ir_ += gauge_rv_ * c;
    } else {
      ground_pose(r_);
    }
  }
  model_ = gs_ = sHs_ = 0.0;
  cg_target_ =
      std::max(0.5 * options_.grad_norm_tol,
               gnorm_ * std::min(options_.forcing, std::pow(gnorm_, options_.forcing_power)));
}

void NewtonRefineProtocol::send_direction(std::vector<OutgoingMessage>& out) {
  if (use_interface_ && options_.sigma_factoring == SigmaFactoring::kShipSolves) {
    return send_solution(true, out);  // z from the holder's solve (after_solution)
  } else if (use_interface_) {
    z_ = interface_->back(X_, iy_r_, ir_);
  } else if (!coarse_) {
    z_ = state_.precondition(X_, r_);
  } else if (!balancing()) {
    // Additive: z = B r + Phi A^+ Phi^T r (Phi^T r identical everywhere).
    z_ = state_.precondition(X_, r_);
    coarse_->expand(X_, coarse_->times_inverse(coarse_r_), z_);
  } else {
    // Balancing, z = C r + (I - C H) B (I - H C) r with C = Phi A^+ Phi^T: here y = B (r - H Phi
    // xi), xi = A^+ Phi^T r, and z' = y + Phi xi is sent; the last term -C H y needs the sum
    // (H Phi)^T y, which rides in this iteration's sum, and is taken off z' and H z' then
    // (after_sums: in the coarse space, H of it is the kept H Phi columns: no exchange).
    const Eigen::VectorXd xi = coarse_->times_inverse(coarse_r_);
    Eigen::MatrixXd t = r_;
    coarse_hphi_->subtract(touched_of(xi), t);
    z_ = state_.precondition(X_, t);
    coarse_hy_ = coarse_hphi_->dot(z_);
    coarse_->expand(X_, xi, z_);
  }
  send_public(z_, kDirection, out);
}

void NewtonRefineProtocol::after_direction(const MessageGate::Inbox& inbox,
                                           std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.cg_s);
  neighbours_into(inbox, zn_);
  w_ = hessian(z_, zn_);
  Eigen::VectorXd vz, vhz;        // V^T z, V^T H z (H z before the grounded pose's rows are zeroed)
  Eigen::VectorXd hvr, hvw, hvq;  // projecting: (H V)^T of r, H z and q
  if (use_interface_) {
    vz.resize(gauge_->size());
    vhz.resize(gauge_->size());
    gauge_->dot(z_, vz.data());
    gauge_->dot(w_, vhz.data());
    if (project_gauge_) {
      const bool first = cg_->iterations() == 0;
      const auto k = static_cast<std::size_t>(gauge_->size());
      hvr.resize(gauge_->size());
      hvw.resize(gauge_->size());
      hvq = Eigen::VectorXd::Zero(gauge_->size());
      for (std::size_t c = 0; c < k; ++c) {
        const auto i = static_cast<Eigen::Index>(c);
        hvr(i) = frobenius_inner(gauge_hv_[c], r_);
        hvw(i) = frobenius_inner(gauge_hv_[c], w_);
        if (!first) hvq(i) = frobenius_inner(gauge_hv_[c], q_);
      }
    } else {
      ground_pose(w_);
    }
  }
  std::vector<double> values{frobenius_inner(r_, z_), frobenius_inner(z_, w_), r_.squaredNorm()};
  if (use_interface_) {  // the interface residual of w, for the ones of q and r
    interface_->forward(X_, w_, iy_w_);
    values.resize(3 + static_cast<std::size_t>(interface_->team_size()), 0.0);
    interface_->add_interface(iy_w_, values.data() + 3);
  }
  if (use_interface_) {
    // ||r - alpha q||^2 of this iteration's update from <r, w>, ||w||^2 and the previous q's
    // products (q = w + beta q_old), so CG stops on its residual right after the update that
    // reached it instead of one exchange and one sum later: with exact interface solves a
    // Newton step's CG is one or two iterations. Not with block Jacobi, whose hundreds of
    // iterations a step would each carry 5 more numbers for one message step saved.
    const bool first = cg_->iterations() == 0;
    values.push_back(frobenius_inner(r_, w_));
    values.push_back(w_.squaredNorm());
    values.push_back(first ? 0.0 : frobenius_inner(r_, q_));
    values.push_back(first ? 0.0 : frobenius_inner(w_, q_));
    values.push_back(first ? 0.0 : q_.squaredNorm());
    values.insert(values.end(), vz.data(), vz.data() + vz.size());
    values.insert(values.end(), vhz.data(), vhz.data() + vhz.size());
    values.insert(values.end(), hvr.data(), hvr.data() + hvr.size());
    values.insert(values.end(), hvw.data(), hvw.data() + hvw.size());
    values.insert(values.end(), hvq.data(), hvq.data() + hvq.size());
  }
  if (coarse_) {  // Phi^T w, for Phi^T q and so Phi^T r by their recurrences
    const std::size_t n = static_cast<std::size_t>(coarse_->size());
    values.resize(3 + (balancing() ? 2 : 1) * n, 0.0);
    coarse_->project(X_, w_, values.data() + 3);
    if (balancing()) {  // and (H Phi)^T y
      const std::vector<int>& touched = coarse_->touched();
      for (std::size_t c = 0; c < touched.size(); ++c)
        values[3 + n + static_cast<std::size_t>(touched[c])] =
            coarse_hy_(static_cast<Eigen::Index>(c));
    }
  }
  broadcast(kSums, values, out);
}

void NewtonRefineProtocol::after_sums(const MessageGate::Inbox& inbox,
                                      std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.cg_s);
  const std::size_t n = static_cast<std::size_t>(coarse_ ? coarse_->size() : 0);
  const std::size_t team =
      use_interface_ ? static_cast<std::size_t>(interface_->team_size()) : std::size_t{0};
  const std::size_t extra = use_interface_ ? 5 : 0;  // the products for ||r_next||
  const std::size_t gk = use_interface_ ? static_cast<std::size_t>(gauge_->size()) : 0;
  const std::size_t gsums = (project_gauge_ ? 5 : 2) * gk;
  std::vector<double> t =
      reduce_in_id_order(inbox, 3 + (balancing() ? 2 : 1) * n + team + extra + gsums);
  if (project_gauge_) project_iteration_off_gauge(t);
  double gamma = t[0], delta = t[1];
  const double rnorm = std::sqrt(std::max(0.0, t[2]));
  Eigen::VectorXd coarse_w;  // Phi^T w
  if (coarse_) coarse_w = Eigen::Map<const Eigen::VectorXd>(t.data() + 3, coarse_->size());
  if (coarse_ && balancing()) {
    // z = z' - Phi eta, H z = w' - H Phi eta with eta = A^+ (H Phi)^T y; the sums follow from
    // the ones of z' and Phi^T w' = (H Phi)^T z'.
    const Eigen::VectorXd eta = coarse_->times_inverse(
        Eigen::Map<const Eigen::VectorXd>(t.data() + 3 + n, coarse_->size()));
    const Eigen::VectorXd a_eta = coarse_->times_matrix(eta);
    gamma -= coarse_r_.dot(eta);
    delta += -2.0 * eta.dot(coarse_w) + eta.dot(a_eta);
    coarse_->expand(X_, -eta, z_);
    coarse_hphi_->subtract(touched_of(eta), w_);
    coarse_w -= a_eta;
  }
  const bool started = cg_->iterations() > 0;
  if (started && rnorm <= cg_target_) return try_step("residual", out);
  if (result_.cg_iterations >= options_.max_cg_iterations) {
    if (started) return try_step("cap", out);
    return finish("max_cg_iterations");
  }
  if (!(gamma > 0)) {  // P r = 0 on a non-zero residual: nothing left to gain
    if (started) return try_step("residual", out);
    return finish("stalled");
  }
  const PipelinedCgIteration it = cg_->begin(gamma, delta);
  if (coarse_) it.update_direction(coarse_w, coarse_q_);
  if (use_interface_) {
    const Eigen::Map<const Eigen::VectorXd> iw(t.data() + 3, static_cast<Eigen::Index>(team));
    it.update_direction(iw, iq_);
    it.update_direction(iy_w_, iy_q_);
  }
  if (use_interface_ && !project_gauge_) {
    const auto k = static_cast<Eigen::Index>(gk);
    it.update_direction(Eigen::Map<const Eigen::VectorXd>(t.data() + 3 + team + extra, k),
                        gauge_vp_);
    it.update_direction(Eigen::Map<const Eigen::VectorXd>(t.data() + 3 + team + extra + gk, k),
                        gauge_vhp_);
  }
  it.update_direction(z_, p_);
  it.update_direction(w_, q_);
  cg_->update_norms(it);
  ++result_.cg_iterations;
  ++step_.cg_iterations;
  const double alpha = it.alpha, pHp = it.pHp;
  const double e_Pe_new = cg_->step_norm2_after(it);
  const bool bounded = radius_ > 0;
  if (!(pHp > 0) || (bounded && e_Pe_new >= radius_ * radius_)) {
    if (!bounded) {
      // Unbounded and not positive curvature: take the Cauchy-like step along p scaled to the
      // current step's size (or p itself on the first iteration) inside a radius from now on.
      radius_ = std::sqrt(std::max(cg_->step_norm2(), cg_->direction_norm2()));
      step_.radius = radius_;
    }
    const double R2 = radius_ * radius_;
    const double tau = cg_->boundary_step(R2);
    s_ += tau * p_;
    if (use_interface_ && !project_gauge_) {
      gauge_vs_ += tau * gauge_vp_;
      gauge_vhs_ += tau * gauge_vhp_;
    }
    model_ += -tau * gamma + 0.5 * tau * tau * pHp;
    gs_ += -tau * gamma;      // <g, p> = -<r_0, p> = -<r, p> = -gamma (CG)
    sHs_ += tau * tau * pHp;  // p is H-conjugate to s
    cg_->set_step_norm2(R2);
    return try_step(pHp > 0 ? "boundary" : "negative_curvature", out);
  }
  s_ += alpha * p_;
  r_ -= alpha * q_;
  if (coarse_) coarse_r_ -= alpha * coarse_q_;
  if (use_interface_) {
    ir_ -= alpha * iq_;
    iy_r_ -= alpha * iy_q_;
    if (!project_gauge_) {
      gauge_vs_ += alpha * gauge_vp_;
      gauge_vhs_ += alpha * gauge_vhp_;
    }
  }
  model_ += -alpha * gamma + 0.5 * alpha * alpha * pHp;
  gs_ += -alpha * gamma;
  sHs_ += alpha * alpha * pHp;
  cg_->set_step_norm2(e_Pe_new);
  cg_->end(it);
  if (extra > 0) {
    const double* e = t.data() + 3 + team;
    const double next = PipelinedCg::next_residual_norm2(it, t[2], e[0], e[1], e[2], e[3], e[4]);
    if (next <= cg_target_ * cg_target_) return try_step("residual", out);
  }
  send_direction(out);
}

void NewtonRefineProtocol::finish(const std::string& why) {
  result_.stop_reason = why;
  if (interface_) result_.interface_analyses = interface_->analyses();
  // The accepted trial's, not needed.
  if (shares_ready_ || interface_carried_) ++result_.pending_factors_unused;
  shares_ready_ = interface_carried_ = false;
  result_.times.wall_s = steady_s() - wall_start_;
  result_.cost = f_;
  result_.grad_norm = gnorm_;
  if (result_.accepted_steps > 0) {
    Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(state_.Y.rows(), state_.Y.cols());
    Eigen::MatrixXd Yn = Eigen::MatrixXd::Zero(state_.Yn.rows(), state_.Yn.cols());
    Y(rows_, Eigen::all) = X_;
    Yn(rows_, Eigen::all) = Xn_;
    state_.reset_iterate(Y, Yn);
  }
  done_ = true;
}

}  // namespace tessera
