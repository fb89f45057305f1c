// The refinement's exchanges once per point: the interface solves' Sigma shares (with the
// gauge's sums) and the coarse correction's matrix, and the step's projection off the gauge.
// The state machine is newton_refine.cpp, the trial point newton_refine_trial.cpp.

#include <Eigen/Cholesky>
#include <stdexcept>
#include <tessera/distributed/newton_refine.hpp>

#include "distributed/coarse_hessian_columns.hpp"
#include "distributed/gauge_space.hpp"
#include "distributed/interface_solve.hpp"
#include "distributed/public_pose_messages.hpp"
#include "distributed/tangent_coarse_space.hpp"

namespace tessera {

void NewtonRefineProtocol::send_interface(std::vector<OutgoingMessage>& out) {
  // This block's share of Sigma at the current point, then its interface residual of -g (the
  // first CG residual), so that the first direction needs no further message step.
  std::vector<double> values = interface_->factor(X_, Xn_, egrad_);
  if (values.front() != 0.0) {
    interface_->forward(X_, -g_, iy_g_);
    std::vector<double> rhat(static_cast<std::size_t>(interface_->team_size()), 0.0);
    interface_->add_interface(iy_g_, rhat.data());
    values.insert(values.end(), rhat.begin() + interface_->offset(),
                  rhat.begin() + interface_->offset() + interface_->size());
  }
  // The gauge's sums at this point (H V: local products, V known on the neighbours' poses).
  gauge_ = std::make_unique<GaugeSpace>(problem_.dim(), X_, Xn_);
  const int k = gauge_->size();
  gauge_hv_.clear();
  for (int c = 0; c < k; ++c) gauge_hv_.push_back(hessian(gauge_->own(c), gauge_->neighbours(c)));
  const std::size_t at = values.size();
  values.resize(at + gauge_share_size(), 0.0);
  double* v = values.data() + at;
  for (int c = 0; c < k; ++c) {
    gauge_->dot(gauge_->own(c), v + c * k);
    gauge_->dot(gauge_hv_[static_cast<std::size_t>(c)], v + k * k + c * k);
  }
  gauge_->dot(g_, v + 2 * k * k);
  broadcast(kInterface, values, out);
}

std::size_t NewtonRefineProtocol::gauge_share_size() const {
  const auto k = static_cast<std::size_t>(problem_.dim() * (problem_.dim() + 1) / 2);
  return 2 * k * k + k;
}

void NewtonRefineProtocol::after_interface(const MessageGate::Inbox& inbox,
                                           std::vector<OutgoingMessage>& out) {
  // Every agent assembles the same Sigma from the same shares in id order.
  std::vector<std::vector<double>> shares;
  ir_g_ = Eigen::VectorXd::Zero(interface_->team_size());
  bool ok = true;
  int b = 0;
  const std::size_t gn = gauge_share_size();
  std::vector<double> gsum(gn, 0.0);
  for (const auto& [sender, m] : inbox) {
    const std::vector<double>& full = std::get<PoseBlockMessage>(m).data;
    if (full.size() <= gn) throw std::runtime_error("newton refine: empty interface share");
    for (std::size_t i = 0; i < gn; ++i) gsum[i] += full[full.size() - gn + i];
    const std::vector<double> v(full.begin(), full.end() - static_cast<std::ptrdiff_t>(gn));
    if (v.front() == 0.0) {
      ok = false;
      shares.push_back({0.0});
    } else {
      const auto n = static_cast<std::size_t>(interface_->block_size(b));
      if (v.size() < n + 1)
        throw std::runtime_error("newton refine: malformed interface share from agent " +
                                 std::to_string(sender));
      shares.emplace_back(v.begin(), v.end() - static_cast<std::ptrdiff_t>(n));
      ir_g_.segment(interface_->block_offset(b), static_cast<Eigen::Index>(n)) =
          Eigen::Map<const Eigen::VectorXd>(v.data() + v.size() - n, static_cast<Eigen::Index>(n));
    }
    ++b;
  }
  if (ok) {
    std::vector<const std::vector<double>*> ptrs;
    for (const auto& v : shares) ptrs.push_back(&v);
    const double eta = options_.interface_shift;
    ok = interface_->assemble(ptrs, {eta, 1e3 * eta, 1e6 * eta});
  }
  interface_due_ = false;
  use_interface_ = ok;
  const int k = gauge_->size();
  const Eigen::Map<const Eigen::MatrixXd> vv(gsum.data(), k, k), vhv(gsum.data() + k * k, k, k);
  gauge_vv_ = 0.5 * (vv + vv.transpose());
  gauge_vhv_ = 0.5 * (vhv + vhv.transpose());
  gauge_vg_ = Eigen::Map<const Eigen::VectorXd>(gsum.data() + 2 * k * k, k);
  use_gauge_ = ok && gauge_vv_.llt().info() == Eigen::Success;
  if (ok) {
    ++result_.interface_factorizations;
  } else {
    ++result_.interface_fallbacks;
    if (refactor_due_) prepare_preconditioner();
  }
  start_cg(out);
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
  const int n = coarse_->size();
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd v, vn;
  const std::vector<int>& touched = coarse_->touched();
  // Balancing also keeps the own rows of H Phi (one column per touched unknown).
  if (options_.coarse_balancing) {
    if (!coarse_hphi_) coarse_hphi_ = std::make_unique<CoarseHessianColumns>(problem_.dim());
    coarse_hphi_->reset(touched.size());
  }
  for (std::size_t c = 0; c < touched.size(); ++c) {
    const int u = touched[c];
    coarse_->unit(X_, Xn_, u, v, vn);
    const Eigen::MatrixXd hv = hessian(v, vn);
    coarse_->project(X_, hv, L.col(u).data());
    if (options_.coarse_balancing) coarse_hphi_->keep(c, hv);
  }
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(n * (n + 1) / 2 + n));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) values.push_back(0.5 * (L(i, j) + L(j, i)));
  const std::size_t at = values.size();
  values.resize(at + static_cast<std::size_t>(n), 0.0);
  coarse_->project(X_, g_, values.data() + at);
  broadcast(kCoarse, values, out);
}

void NewtonRefineProtocol::after_coarse(const MessageGate::Inbox& inbox,
                                        std::vector<OutgoingMessage>& out) {
  const int n = coarse_->size();
  const std::vector<double> t =
      reduce_in_id_order(inbox, static_cast<std::size_t>(n * (n + 1) / 2 + n));
  Eigen::MatrixXd A(n, n);
  std::size_t at = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) A(i, j) = A(j, i) = t[at++];
  coarse_inverse_ = coarse_->pseudo_inverse(A);
  coarse_matrix_ = A;
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

}  // namespace tessera
