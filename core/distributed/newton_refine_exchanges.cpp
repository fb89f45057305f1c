// The refinement's exchanges once per point: the interface solves' Sigma shares (with the
// gauge's sums) and the coarse correction's matrix, and the step's projection off the gauge.
// The state machine is newton_refine.cpp, the trial point newton_refine_trial.cpp.

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/problem/pose_kernels.hpp>
#include <utility>

#include "distributed/coarse_hessian_columns.hpp"
#include "distributed/gauge_space.hpp"
#include "distributed/interface_solve.hpp"
#include "distributed/public_pose_messages.hpp"
#include "distributed/tangent_coarse_space.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera {

namespace {

// Sigma assembled from the agents' shares in id order and factored with the refinement's
// shifts eta, 1e3 eta, 1e6 eta (the first positive definite one); false where none was.
bool assemble_sigma(InterfaceSolve& interface, const std::vector<std::vector<double>>& shares,
                    double eta) {
  std::vector<const std::vector<double>*> ptrs;
  ptrs.reserve(shares.size());
  for (const auto& v : shares) ptrs.push_back(&v);
  return interface.assemble(ptrs, {eta, 1e3 * eta, 1e6 * eta});
}

}  // namespace

void NewtonRefineProtocol::send_interface(std::vector<OutgoingMessage>& out) {
  const std::vector<double> values = interface_share(X_, Xn_, egrad_, g_, false);
  if (options_.sigma_factoring != SigmaFactoring::kShipSolves)
    return broadcast(kInterface, values, out);
  send_to_holder(kInterface, values, brief_share(values), out);
}

std::vector<double> NewtonRefineProtocol::interface_share(const Eigen::MatrixXd& X,
                                                          const Eigen::MatrixXd& Xn,
                                                          const Eigen::MatrixXd& egrad,
                                                          const Eigen::MatrixXd& g, bool pending) {
  // This block's share of Sigma at the point, then its interface residual of -g (the first CG
  // residual), so that the first direction needs no further message step.
  charge_to(&result_.times.factor_s);
  // With the shares in hand (the accepted trial's sum carried them, kShipFactor) the block is
  // factored at this point already: only its flag goes out, and agent 0's Sigma factor.
  std::vector<double> values =
      shares_ready_
          ? std::vector<double>{next_shares_.at(static_cast<std::size_t>(state_.id())).front()}
      : pending ? interface_->factor_pending(X, Xn, egrad)
                : interface_->factor(X, Xn, egrad);
  if (shares_ready_ && state_.id() == kSigmaHolder) {
    const std::vector<double> sigma = factor_shipped_sigma();
    values.insert(values.end(), sigma.begin(), sigma.end());
    charge_to(&result_.times.factor_s);
  }
  // The gauge at this point (H V: local products, V known on the neighbours' poses).
  gauge_ = std::make_unique<GaugeSpace>(problem_.dim(), X, Xn);
  const int k = gauge_->size();
  gauge_hv_.clear();
  for (int c = 0; c < k; ++c)
    gauge_hv_.push_back(hessian_at(X, egrad, gauge_->own(c), gauge_->neighbours(c)));
  if (values.front() != 0.0) {
    // The own segment of the team's interface residual of -g, then (projecting the gauge) of
    // each column of V and of H V, from the block's forward solves.
    const auto own = [&](const Eigen::MatrixXd& v, Eigen::VectorXd& y) {
      interface_->forward(X, v, y, pending);
      std::vector<double> rhat(static_cast<std::size_t>(interface_->team_size()), 0.0);
      interface_->add_interface(y, rhat.data(), pending);
      values.insert(values.end(), rhat.begin() + interface_->offset(),
                    rhat.begin() + interface_->offset() + interface_->size());
    };
    own(-g, iy_g_);
    if (options_.project_gauge) {
      Eigen::VectorXd y;
      for (int c = 0; c < k; ++c) {
        own(gauge_->own(c), y);
        if (c == 0) gauge_fv_.resize(y.size(), k);
        gauge_fv_.col(c) = y;
      }
      for (int c = 0; c < k; ++c) {
        own(gauge_hv_[static_cast<std::size_t>(c)], y);
        if (c == 0) gauge_fhv_.resize(y.size(), k);
        gauge_fhv_.col(c) = y;
      }
    }
  }
  // The gauge's sums: V^T V, V^T H V, V^T g (and (H V)^T (H V) when projecting).
  const std::size_t at = values.size();
  values.resize(at + gauge_share_size(), 0.0);
  double* v = values.data() + at;
  for (int c = 0; c < k; ++c) {
    gauge_->dot(gauge_->own(c), v + c * k);
    gauge_->dot(gauge_hv_[static_cast<std::size_t>(c)], v + k * k + c * k);
  }
  gauge_->dot(g, v + 2 * k * k);
  if (options_.project_gauge)
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j)
        v[2 * k * k + k + i * k + j] = frobenius_inner(gauge_hv_[static_cast<std::size_t>(i)],
                                                       gauge_hv_[static_cast<std::size_t>(j)]);
  return values;
}

std::vector<double> NewtonRefineProtocol::brief_share(const std::vector<double>& values) const {
  // The flag, the interface residuals (where the block factored) and the gauge's sums.
  const std::size_t tail =
      gauge_share_size() + (values.front() != 0.0 ? share_tail() : std::size_t{0});
  std::vector<double> brief{values.front()};
  brief.insert(brief.end(), values.end() - static_cast<std::ptrdiff_t>(tail), values.end());
  return brief;
}

void NewtonRefineProtocol::send_to_holder(std::uint32_t step, const std::vector<double>& full,
                                          const std::vector<double>& brief,
                                          std::vector<OutgoingMessage>& out) {
  // Agent 0 alone assembles Sigma: it receives the whole shares, the others each share's flag,
  // interface residuals and gauge sums only. Always the same agent: its Sigma pattern and
  // symbolic analysis are laid out once (each first assemble() on an agent does both; taking
  // turns on city10000's 3 points cost 183 M instructions in assemble() against 111 M).
  const int id = state_.id();
  gate_.add(id, message_round_, step, make_reduction_message(id, message_round_, step, full));
  for (int b = 0; b < layout_.num_blocks; ++b) {
    if (b == id) continue;
    out.push_back(addressed_to(
        static_cast<std::uint32_t>(b),
        make_reduction_message(id, message_round_, step, b == kSigmaHolder ? full : brief)));
  }
  gate_.expect(message_round_, step, everyone_);
  ++result_.reductions;
}

void NewtonRefineProtocol::swap_point_parts() {
  std::swap(gauge_, trial_gauge_);
  std::swap(gauge_hv_, trial_gauge_hv_);
  std::swap(iy_g_, trial_iy_g_);
  std::swap(gauge_fv_, trial_gauge_fv_);
  std::swap(gauge_fhv_, trial_gauge_fhv_);
}

void NewtonRefineProtocol::use_carried_shares(std::vector<OutgoingMessage>& out) {
  const std::vector<std::vector<double>> carried = std::move(next_shares_);
  next_shares_.clear();
  interface_carried_ = false;
  ++result_.interface_shares_carried;
  std::vector<std::pair<int, const std::vector<double>*>> in;
  for (std::size_t b = 0; b < carried.size(); ++b)
    in.emplace_back(static_cast<int>(b), &carried[b]);
  use_interface_shares(in, out);
}

std::size_t NewtonRefineProtocol::share_tail() const {
  // A share's interface residuals (of -g, and projecting the gauge of V and H V): per block.
  const auto per = static_cast<std::size_t>(options_.project_gauge ? 1 + 2 * gauge_->size() : 1);
  return per * static_cast<std::size_t>(interface_->size());
}

void NewtonRefineProtocol::send_solution(bool ok, std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.sigma_s);
  if (state_.id() == kSigmaHolder) {
    Eigen::VectorXd u;
    if (ok) u = interface_->solve(ir_);
    for (int b = 0; b < layout_.num_blocks; ++b) {
      std::vector<double> values{ok ? 1.0 : 0.0, ok && interface_->grounded() ? 1.0 : 0.0};
      if (ok)
        values.insert(values.end(), u.data() + interface_->block_offset(b),
                      u.data() + interface_->block_offset(b) + interface_->block_size(b));
      PoseBlockMessage m = make_reduction_message(kSigmaHolder, message_round_, kSolution, values);
      if (b == kSigmaHolder) {
        gate_.add(kSigmaHolder, message_round_, kSolution, m);
        continue;
      }
      out.push_back(addressed_to(static_cast<std::uint32_t>(b), std::move(m)));
    }
  }
  gate_.expect(message_round_, kSolution, {kSigmaHolder});
  ++result_.solution_steps;
}

void NewtonRefineProtocol::after_solution(const MessageGate::Inbox& inbox,
                                          std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.cg_s);
  const auto found = inbox.find(kSigmaHolder);
  const auto* m = found == inbox.end() ? nullptr : std::get_if<PoseBlockMessage>(&found->second);
  const std::size_t own = static_cast<std::size_t>(interface_->size());
  if (!m || m->data.size() < 2 || m->data.size() != (m->data[0] != 0.0 ? 2 + own : 2))
    throw std::runtime_error("newton refine: malformed interface solution from agent " +
                             std::to_string(kSigmaHolder));
  const std::vector<double>& v = m->data;
  if (v[0] == 0.0) {  // no positive definite Sigma at this point: block Jacobi, on every agent
    verdict_due_ = false;
    take_interface_verdict(false);
    return start_cg(out);
  }
  if (verdict_due_) {  // the point's first solution: Sigma factored on the holder
    verdict_due_ = false;
    interface_->adopt_remote_sigma(v[1] != 0.0);
    take_interface_verdict(true);
    reset_cg();
  }
  z_ = interface_->back_own(X_, iy_r_, v.data() + 2);
  send_public(z_, kDirection, out);
}

std::vector<double> NewtonRefineProtocol::factor_shipped_sigma() {
  charge_to(&result_.times.sigma_s);
  bool ok = true;
  for (const auto& v : next_shares_) ok = ok && !v.empty() && v.front() != 0.0;
  if (ok) {
    ok = assemble_sigma(*interface_, next_shares_, options_.interface_shift);
    ++result_.sigma_factorizations;
  }
  if (!ok) return {0.0};
  return interface_->sigma_values();
}

std::size_t NewtonRefineProtocol::gauge_share_size() const {
  const auto k = static_cast<std::size_t>(problem_.dim() * (problem_.dim() + 1) / 2);
  return 2 * k * k + k + (options_.project_gauge ? k * k : 0);
}

void NewtonRefineProtocol::after_interface(const MessageGate::Inbox& inbox,
                                           std::vector<OutgoingMessage>& out) {
  std::vector<std::pair<int, const std::vector<double>*>> shares;
  for (const auto& [sender, m] : inbox)
    shares.emplace_back(sender, &std::get<PoseBlockMessage>(m).data);
  use_interface_shares(shares, out);
}

void NewtonRefineProtocol::use_interface_shares(
    const std::vector<std::pair<int, const std::vector<double>*>>& inbox,
    std::vector<OutgoingMessage>& out) {
  // Every agent assembles the same Sigma from the same shares in id order.
  charge_to(&result_.times.sigma_s);
  std::vector<std::vector<double>> shares;
  ir_g_ = Eigen::VectorXd::Zero(interface_->team_size());
  const int k = gauge_->size();
  const Eigen::Index per = options_.project_gauge ? 1 + 2 * k : 1;  // rhat vectors a share has
  if (options_.project_gauge) {
    gauge_rv_ = Eigen::MatrixXd::Zero(interface_->team_size(), k);
    gauge_rhv_ = Eigen::MatrixXd::Zero(interface_->team_size(), k);
  }
  bool ok = true;
  int b = 0;
  const std::size_t gn = gauge_share_size();
  std::vector<double> gsum(gn, 0.0);
  for (const auto& [sender, data] : inbox) {
    const std::vector<double>& full = *data;
    if (full.size() <= gn) throw std::runtime_error("newton refine: empty interface share");
    for (std::size_t i = 0; i < gn; ++i) gsum[i] += full[full.size() - gn + i];
    const std::vector<double> v(full.begin(), full.end() - static_cast<std::ptrdiff_t>(gn));
    if (v.front() == 0.0) {
      ok = false;
      shares.push_back({0.0});
    } else {
      // shares_ready_: v is the flag (agent 0: then its Sigma factor) and the residuals.
      const Eigen::Index n = interface_->block_size(b);
      const auto tail = static_cast<std::size_t>(per * n);
      if (v.size() < tail + 1)
        throw std::runtime_error("newton refine: malformed interface share from agent " +
                                 std::to_string(sender));
      shares.emplace_back(v.begin(), v.end() - static_cast<std::ptrdiff_t>(tail));
      const double* rh = v.data() + v.size() - tail;
      const Eigen::Index o = interface_->block_offset(b);
      ir_g_.segment(o, n) = Eigen::Map<const Eigen::VectorXd>(rh, n);
      for (int c = 0; per > 1 && c < k; ++c) {
        gauge_rv_.col(c).segment(o, n) = Eigen::Map<const Eigen::VectorXd>(rh + (1 + c) * n, n);
        gauge_rhv_.col(c).segment(o, n) =
            Eigen::Map<const Eigen::VectorXd>(rh + (1 + k + c) * n, n);
      }
    }
    ++b;
  }
  const bool all_flags = ok;  // every block factored (each share's flag, known to all)
  if (ok && shares_ready_) {
    // Agent 0's factor of Sigma from the accepted trial's shares (factored there already on
    // agent 0): taken as it is where this agent's Sigma has the same analysis, else assembled
    // and factored here from the same shares (the same bits either way).
    const std::vector<double>& zero = shares.front();
    if (zero.size() < 2 || zero[1] == 0.0) {
      ok = false;  // agent 0 found no positive definite shift: neither would this agent
    } else if (state_.id() != 0) {
      if (interface_->import_sigma(zero.data() + 1, zero.size() - 1)) {
        ++result_.sigma_imports;
      } else {
        ok = assemble_sigma(*interface_, next_shares_, options_.interface_shift);
        ++result_.sigma_factorizations;
      }
    }
  } else if (ok && (options_.sigma_factoring != SigmaFactoring::kShipSolves ||
                    state_.id() == kSigmaHolder)) {
    ok = assemble_sigma(*interface_, shares, options_.interface_shift);
    ++result_.sigma_factorizations;
  }
  shares_ready_ = false;
  next_shares_.clear();
  interface_due_ = false;
  const Eigen::Map<const Eigen::MatrixXd> vv(gsum.data(), k, k), vhv(gsum.data() + k * k, k, k);
  gauge_vv_ = 0.5 * (vv + vv.transpose());
  gauge_vhv_ = 0.5 * (vhv + vhv.transpose());
  gauge_vg_ = Eigen::Map<const Eigen::VectorXd>(gsum.data() + 2 * k * k, k);
  if (options_.project_gauge) {
    const Eigen::Map<const Eigen::MatrixXd> kk(gsum.data() + 2 * k * k + k, k, k);
    gauge_hvhv_ = 0.5 * (kk + kk.transpose());
  }
  if (options_.sigma_factoring == SigmaFactoring::kShipSolves && all_flags) {
    // Only the holder knows whether Sigma factored: its first solution says so.
    if (state_.id() == kSigmaHolder) {
      if (ok) {
        take_interface_verdict(true);
        reset_cg();
      }
      return send_solution(ok, out);
    }
    verdict_due_ = true;
    return send_solution(true, out);  // waits for the holder's
  }
  take_interface_verdict(ok);
  start_cg(out);
}

void NewtonRefineProtocol::take_interface_verdict(bool ok) {
  use_interface_ = ok;
  use_gauge_ = ok && gauge_vv_.llt().info() == Eigen::Success;
  project_gauge_ = use_gauge_ && options_.project_gauge;
  if (ok) {
    ++result_.interface_factorizations;
  } else {
    ++result_.interface_fallbacks;
    if (refactor_due_) prepare_preconditioner();
  }
}

void NewtonRefineProtocol::ground_pose(Eigen::MatrixXd& v) const {
  // With the interface solves the CG solves the Newton equation of f with the grounded pose
  // held (interface_solve.hpp): its residual and H's products are zero there, as z is.
  const Eigen::Index k = interface_->grounded_pose();
  if (k >= 0) v.middleCols(k * (problem_.dim() + 1), problem_.dim() + 1).setZero();
}

void NewtonRefineProtocol::send_coarse(std::vector<OutgoingMessage>& out) {
  // This agent's rows of A = Phi^T H Phi: column u is Phi^T (H Phi e_u) over the own poses,
  // with Phi e_u on the own poses and the neighbour copies (the agent knows both). The share
  // is symmetrized (only the sum over the agents is symmetric); upper triangle, then Phi^T g.
  charge_to(&result_.times.factor_s);
  const int n = coarse_->size();
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  // Without the multipliers: LD, the share of Phi^T Proj(2 V Q) Phi, is the matrix inverted;
  // L (Hess f's) is still needed by balancing (its H Phi columns and A's products).
  const bool data_part = !options_.coarse_multipliers;
  // The data part's matrix from an earlier point: only Phi^T g is summed at this one.
  coarse_fresh_ = !keeps_coarse_matrix(data_part, result_.coarse_assemblies, coarse_kept_steps_,
                                       options_.coarse_keep_steps);
  if (!coarse_fresh_) {
    std::vector<double> values(static_cast<std::size_t>(n), 0.0);
    coarse_->project(X_, g_, values.data());
    return broadcast(kCoarse, values, out);
  }
  coarse_kept_steps_ = 0;
  const bool galerkin = !data_part || options_.coarse_balancing;
  Eigen::MatrixXd LD = data_part ? Eigen::MatrixXd::Zero(n, n) : Eigen::MatrixXd();
  const std::vector<int>& touched = coarse_->touched();
  // Balancing also keeps the own rows of H Phi (one column per touched unknown).
  if (options_.coarse_balancing) {
    if (!coarse_hphi_) coarse_hphi_ = std::make_unique<CoarseHessianColumns>(problem_.dim());
    coarse_hphi_->reset(touched.size());
  }
  // Each column's Hessian product on the poses it reaches only: Phi e_u lives on its piece's
  // poses S (own) and Sn (neighbour copies), so H Phi e_u = Proj(2 v Q_BB + 2 vn Q_NB) - W is
  // non-zero only on the own poses J that share a measurement with S or Sn (Q_BB's and Q_NB's
  // pattern), and Phi^T of it is a sum over J. The products per pose are the full product's,
  // so the column is the same; its cost is |J| poses, not the block. And a piece's generators
  // share one product: v = E L with L the piece's lift (lift_on), so 2 v Q = E (2 L Q), whose
  // rows each generator's E copies (apply_generator): the same sums, once per piece.
  const SparseMatrix& qbb = problem_.data_matrix();
  const SparseMatrix& qnb = problem_.neighbor_matrix();
  const Eigen::Index w = problem_.dim() + 1;
  const auto rows = static_cast<Eigen::Index>(X_.rows());
  const auto own_poses = static_cast<Eigen::Index>(problem_.owned().size());
  // Own poses that share a measurement with each neighbour copy (Q_NB's pattern, by row).
  std::vector<std::vector<Eigen::Index>> own_of_neighbour(problem_.neighbors().size());
  for (Eigen::Index col = 0; col < qnb.outerSize(); col += w)
    for (SparseMatrix::InnerIterator it(qnb, col); it; ++it)
      if (it.row() % w == 0)
        own_of_neighbour[static_cast<std::size_t>(it.row() / w)].push_back(col / w);
  std::vector<char> in_j(static_cast<std::size_t>(own_poses), 0);
  Eigen::MatrixXd hv = Eigen::MatrixXd::Zero(rows, X_.cols());
  std::vector<Eigen::Index> J;
  // On J's poses: the point and Euclidean gradient, the piece's lift and 2 lift Q, a column's
  // v and H v.
  Eigen::MatrixXd XJ, GJ, LJ, MJ, VJ, HJ;
  // The piece's lift, zero but on its slots (set and cleared per piece).
  Eigen::MatrixXd lift = Eigen::MatrixXd::Zero(rows + 1, X_.cols());
  Eigen::MatrixXd liftn = Eigen::MatrixXd::Zero(rows + 1, Xn_.cols());
  std::vector<Eigen::Index> own_slots, neighbour_slots;
  int piece = -1;
  for (std::size_t c = 0; c < touched.size(); ++c) {
    const int u = touched[c];
    if (u / coarse_->generators() != piece) {  // a new piece: its poses J and its product
      for (Eigen::Index i : own_slots) lift.middleCols(i * w, w).setZero();
      for (Eigen::Index i : neighbour_slots) liftn.middleCols(i * w, w).setZero();
      piece = u / coarse_->generators();
      own_slots = coarse_->own_slots(piece);
      neighbour_slots = coarse_->neighbour_slots(piece);
      coarse_->lift_on(X_, Xn_, piece, own_slots, neighbour_slots, lift, liftn);
      for (Eigen::Index j : J) in_j[static_cast<std::size_t>(j)] = 0;
      J.clear();
      for (Eigen::Index i : own_slots)
        for (Eigen::Index q = 0; q < w; ++q)
          for (SparseMatrix::InnerIterator it(qbb, i * w + q); it; ++it)
            if (!in_j[static_cast<std::size_t>(it.row() / w)]) {
              in_j[static_cast<std::size_t>(it.row() / w)] = 1;
              J.push_back(it.row() / w);
            }
      for (Eigen::Index i : neighbour_slots)
        for (Eigen::Index j : own_of_neighbour[static_cast<std::size_t>(i)])
          if (!in_j[static_cast<std::size_t>(j)]) {
            in_j[static_cast<std::size_t>(j)] = 1;
            J.push_back(j);
          }
      std::sort(J.begin(), J.end());
      const auto nj = static_cast<Eigen::Index>(J.size());
      XJ.resize(rows, w * nj);
      GJ.resize(rows, w * nj);
      LJ.resize(rows + 1, w * nj);
      MJ.setZero(rows + 1, w * nj);
      for (Eigen::Index a = 0; a < nj; ++a) {
        const Eigen::Index from = J[static_cast<std::size_t>(a)] * w;
        XJ.middleCols(a * w, w) = X_.middleCols(from, w);
        GJ.middleCols(a * w, w) = egrad_.middleCols(from, w);
        LJ.middleCols(a * w, w) = lift.middleCols(from, w);
        for (Eigen::Index q = 0; q < w; ++q) {
          for (SparseMatrix::InnerIterator it(qbb, from + q); it; ++it)
            MJ.col(a * w + q) += (2.0 * it.value()) * lift.col(it.row());
          if (liftn.cols() > 0)
            for (SparseMatrix::InnerIterator it(qnb, from + q); it; ++it)
              MJ.col(a * w + q) += (2.0 * it.value()) * liftn.col(it.row());
        }
      }
    }
    const int generator = u % coarse_->generators();
    coarse_->apply_generator(generator, MJ, HJ);
    const auto nj = static_cast<Eigen::Index>(J.size());
    const LiftedManifold manifold(static_cast<int>(rows), problem_.dim(),
                                  static_cast<std::size_t>(nj));
    if (data_part) {
      const Eigen::MatrixXd DJ = manifold.tangent_project(XJ, HJ);
      for (Eigen::Index a = 0; a < nj; ++a)
        hv.middleCols(J[static_cast<std::size_t>(a)] * w, w) = DJ.middleCols(a * w, w);
      coarse_->project(X_, hv, J, LD.col(u).data());
    }
    if (galerkin) {
      coarse_->apply_generator(generator, LJ, VJ);
      apply_hessian_projection(XJ, GJ, VJ, problem_.dim(), HJ);
      HJ = manifold.tangent_project(XJ, std::move(HJ));  // in place: the same sums
      for (Eigen::Index a = 0; a < nj; ++a)
        hv.middleCols(J[static_cast<std::size_t>(a)] * w, w) = HJ.middleCols(a * w, w);
      coarse_->project(X_, hv, J, L.col(u).data());
      if (options_.coarse_balancing) coarse_hphi_->keep(c, hv, J);
    }
    for (Eigen::Index j : J) hv.middleCols(j * w, w).setZero();  // zero again, off J too
  }
  std::vector<double> values;
  values.reserve(2 * coarse_->packed_size() + static_cast<std::size_t>(n));
  if (data_part) coarse_->pack(LD, values);
  if (galerkin) coarse_->pack(L, values);
  const std::size_t at = values.size();
  values.resize(at + static_cast<std::size_t>(n), 0.0);
  coarse_->project(X_, g_, values.data() + at);
  broadcast(kCoarse, values, out);
}

void NewtonRefineProtocol::after_coarse(const MessageGate::Inbox& inbox,
                                        std::vector<OutgoingMessage>& out) {
  charge_to(&result_.times.sigma_s);
  const int n = coarse_->size();
  const std::size_t packed = coarse_->packed_size();
  if (!coarse_fresh_) {
    const std::vector<double> t = reduce_in_id_order(inbox, static_cast<std::size_t>(n));
    coarse_g_ = Eigen::Map<const Eigen::VectorXd>(t.data(), n);
    coarse_due_ = false;
    return start_cg(out);
  }
  const bool data_part = !options_.coarse_multipliers;
  const bool both = data_part && options_.coarse_balancing;  // send_coarse's order
  const std::size_t at = both ? 2 * packed : packed;
  const std::vector<double> t = reduce_in_id_order(inbox, at + static_cast<std::size_t>(n));
  if (both)
    coarse_->set_matrices(t.data(), t.data() + packed);
  else
    coarse_->set_matrix(t.data());
  coarse_g_ = Eigen::Map<const Eigen::VectorXd>(t.data() + at, n);
  coarse_due_ = false;
  ++result_.coarse_assemblies;
  start_cg(out);
}

void NewtonRefineProtocol::project_step_off_gauge() {
  // s - V c with c = (V^T V)^-1 V^T s: <g, s - V c> = <g, s> - c^T V^T g and
  // <s - V c, H (s - V c)> = <s, H s> - 2 c^T V^T H s + c^T V^T H V c, every term a sum all
  // agents hold, so every agent takes the same model.
  const Eigen::VectorXd c = gauge_vv_.llt().solve(gauge_vs_);
  gauge_->subtract(c, s_);
  gs_ -= c.dot(gauge_vg_);
  sHs_ += -2.0 * c.dot(gauge_vhs_) + c.dot(gauge_vhv_ * c);
  model_ = gs_ + 0.5 * sHs_;
}

void NewtonRefineProtocol::project_iteration_off_gauge(std::vector<double>& t) {
  // The CG on the tangent vectors orthogonal to V with the preconditioner P M P (P the
  // projection off V, M the grounded Sigma's inverse: positive definite there): z' = z - V a,
  // a = (V^T V)^-1 V^T z; H z' = H z - (H V) a; its projection w' = H z' - V b with
  // b = (V^T V)^-1 V^T H z'. The interface residuals of w' follow from those of V and H V. The
  // sums, from V^T z, V^T H z and (H V)^T of r, H z and the previous q (r and q are
  // orthogonal to V): <z', H z'> = <z, H z> - 2 a^T V^T H z + a^T V^T H V a; <r, w'> =
  // <r, H z> - a^T (H V)^T r; ||w'||^2 = ||H z||^2 - 2 a^T (H V)^T H z + a^T (H V)^T H V a
  // - b^T V^T V b; <w', q> = <H z, q> - a^T (H V)^T q; <r, z'> = <r, z>.
  const int k = gauge_->size();
  const Eigen::Index team = interface_->team_size();
  double* e = t.data() + 3 + team;
  const Eigen::Map<const Eigen::VectorXd> vz(e + 5, k), vhz(e + 5 + k, k), hvr(e + 5 + 2 * k, k),
      hvw(e + 5 + 3 * k, k), hvq(e + 5 + 4 * k, k);
  const Eigen::LLT<Eigen::MatrixXd> G(gauge_vv_);
  const Eigen::VectorXd a = G.solve(vz);
  const Eigen::VectorXd b = G.solve(vhz - gauge_vhv_ * a);
  gauge_->subtract(a, z_);
  for (int c = 0; c < k; ++c) w_ -= a(c) * gauge_hv_[static_cast<std::size_t>(c)];
  gauge_->subtract(b, w_);
  iy_w_ -= gauge_fhv_ * a + gauge_fv_ * b;
  Eigen::Map<Eigen::VectorXd>(t.data() + 3, team) -= gauge_rhv_ * a + gauge_rv_ * b;
  t[1] += -2.0 * a.dot(vhz) + a.dot(gauge_vhv_ * a);
  e[0] -= a.dot(hvr);
  e[1] += -2.0 * a.dot(hvw) + a.dot(gauge_hvhv_ * a) - b.dot(gauge_vv_ * b);
  e[3] -= a.dot(hvq);
}

}  // namespace tessera
