// The distributed rounding's exact translation solve through the team's interface
// (distributed/translation_interface_solve.hpp): with the rounded rotations fixed, the
// translations minimise t^T L t - 2 b^T t, L the weighted translation Laplacian, which does not
// depend on the rotations. So each block factors its L_BB (interior first, interface last) and
// sends its Schur complement on the interface with the Gram matrix, before any rotation is
// known; after the rotations' exchange the first agent gathers the blocks' interface residuals
// and sends every agent the interface translations u = Sigma^-1 rhat (it alone factors Sigma
// from DistributedRoundingOptions::interface_one_factor_min_poses interface poses on: five
// agents factoring the same Sigma were half the rounding's instructions on torus3D; below,
// every agent factors it and one all-agent sum of the residuals gives each u), and each
// back-substitutes its interior. The neighbours' public translations are rows of u, bit for
// bit what their owners hold. Against the CG (distributed_rounding.cpp, translations()): 3 message
// steps (share, residual, cost) instead of its warm start's 2, a start step per restart and one per
// iteration, and the exact solve instead of one within cost_bound().

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <optional>
#include <stdexcept>
#include <string>
#include <tessera/distributed/message_gate.hpp>
#include <unordered_map>
#include <variant>

#include "distributed/translation_interface_solve.hpp"
#include "runtime/distributed_rounding.hpp"

namespace tessera::agent {

void DistributedRounding::send_interface_share() {
  const std::size_t cap = options_.interface_max_poses;
  if (cap == 0 || everyone_.size() < 2) return;
  const auto team = static_cast<std::size_t>(interface_pose_count(layout_));
  if (team == 0 || team > cap) return;
  one_factor_ = team >= options_.interface_one_factor_min_poses;
  // L's rows of the owned poses, from the measurements as the CG builds them (no pose fixed:
  // the interface solve grounds the team's first interface pose, run() shifts to pose 0).
  std::unordered_map<std::size_t, Eigen::Index> slot;
  for (std::size_t s = 0; s < own_.size(); ++s) slot.emplace(own_[s], static_cast<Eigen::Index>(s));
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<TranslationInterfaceSolve::Coupling> cut;
  for (const Measurement& e : local_.measurements) {
    auto si = slot.find(e.i), sj = slot.find(e.j);
    const bool oi = si != slot.end(), oj = sj != slot.end();
    if (oi) entries.emplace_back(si->second, si->second, e.tau);
    if (oj) entries.emplace_back(sj->second, sj->second, e.tau);
    if (oi && oj) {
      entries.emplace_back(si->second, sj->second, -e.tau);
      entries.emplace_back(sj->second, si->second, -e.tau);
    } else if (oi) {
      cut.push_back({e.i, e.j, -e.tau});
    } else if (oj) {
      cut.push_back({e.j, e.i, -e.tau});
    }
  }
  interface_ = std::make_unique<TranslationInterfaceSolve>(own_, entries, cut, layout_,
                                                           static_cast<int>(self_));
  interface_share_ = interface_->share();
  mail_.send_all({OutgoingMessage{
      make_reduction_message(static_cast<int>(self_), 0, kInterfaceShare, interface_share_),
      true,
      {}}});
}

bool DistributedRounding::take_interface_shares() {
  if (!interface_) return false;
  auto got = mail_.gather(kInterfaceShare, 0, others());
  std::vector<const std::vector<double>*> blocks;
  for (std::uint32_t a : everyone_) {
    if (a == self_) {
      blocks.push_back(&interface_share_);
      continue;
    }
    const auto* m = std::get_if<PoseBlockMessage>(&got.at(a));
    if (!m)
      throw std::runtime_error("rounding: interface share of the wrong kind from agent " +
                               std::to_string(a));
    blocks.push_back(&m->data);
  }
  // With one factor only sigma_agent() factors Sigma; the shares' check is the same everywhere.
  // A factor that fails is announced with u, or fails alike on every agent
  // (interface_translations()).
  const bool factor = !one_factor_ || self_ == sigma_agent();
  if (!interface_->assemble(blocks, factor) && (!factor || !interface_->assemble(blocks, false)))
    interface_.reset();
  return interface_ != nullptr;
}

std::optional<double> DistributedRounding::interface_translations() {
  // The exact solve is one step of the stage: it is a progress point like a CG iteration (the
  // coordinator sees the rounding begin; test builds can stop an agent here).
  mail_.report_progress(ProgressStage::kRounding, 0, 0.0);
  const Eigen::Index d = d_, m = static_cast<Eigen::Index>(own_.size());
  std::unordered_map<std::size_t, Eigen::Index> slot;
  for (Eigen::Index s = 0; s < m; ++s) slot.emplace(own_[static_cast<std::size_t>(s)], s);
  // b: the owned rows of the whole right-hand side (pose 0's included; it sums to zero over
  // the team, so the grounded solve solves every row).
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(m, d);
  for (const Measurement& e : local_.measurements) {
    const Eigen::RowVectorXd c = (poses_.at(e.i).R * e.t).transpose();
    auto si = slot.find(e.i), sj = slot.find(e.j);
    if (si != slot.end()) b.row(si->second) -= e.tau * c;
    if (sj != slot.end()) b.row(sj->second) += e.tau * c;
  }
  Eigen::MatrixXd y;
  interface_->forward(b, y);
  const Eigen::MatrixXd rhat = interface_->interface_residual(y);
  const std::vector<double> values(rhat.data(), rhat.data() + rhat.size());
  const PoseBlockMessage mine =
      make_reduction_message(static_cast<int>(self_), 0, kInterfaceResidual, values);
  // With one factor (one_factor_), only sigma_agent() holds Sigma's factor: it gathers the
  // residuals, solves u = Sigma^-1 rhat and sends u to all, flag first (0: its factor failed,
  // the CG runs everywhere). The same bits as every agent's own factor of the same Sigma on the
  // same residuals gave. Otherwise every agent gathers every residual and solves itself.
  const Eigen::Index team = interface_->team_size();
  Eigen::MatrixXd u;
  if (one_factor_ && self_ != sigma_agent()) {
    mail_.send_all({addressed_to(sigma_agent(), mine)});
    auto sol = mail_.gather(kInterfaceSolution, 0, {sigma_agent()});
    const auto* msg = std::get_if<PoseBlockMessage>(&sol.at(sigma_agent()));
    if (!msg || msg->data.empty())
      throw std::runtime_error("rounding: interface solution of the wrong kind");
    if (msg->data[0] == 0.0) return std::nullopt;
    if (msg->data.size() != static_cast<std::size_t>(1 + team * d))
      throw std::runtime_error("rounding: interface solution of the wrong size");
    u = Eigen::Map<const Eigen::MatrixXd>(msg->data.data() + 1, team, d);
  } else {
    if (one_factor_)
      mail_.next_gather_is_a_step();
    else
      mail_.send_all({OutgoingMessage{mine, true, {}}});
    auto got = mail_.gather(kInterfaceResidual, 0, others());
    Eigen::MatrixXd R(team, d);
    for (std::uint32_t a : everyone_) {
      const auto* msg = a == self_ ? &mine : std::get_if<PoseBlockMessage>(&got.at(a));
      const Eigen::Index n = interface_->block_size(static_cast<int>(a));
      if (!msg || msg->data.size() != static_cast<std::size_t>(n * d))
        throw std::runtime_error("rounding: interface residual of the wrong size from agent " +
                                 std::to_string(a));
      R.middleRows(interface_->block_offset(static_cast<int>(a)), n) =
          Eigen::Map<const Eigen::MatrixXd>(msg->data.data(), n, d);
    }
    if (interface_->ready()) u = interface_->solve_interface(R);
    if (one_factor_) {
      std::vector<double> sent(1, interface_->ready() ? 1.0 : 0.0);
      sent.insert(sent.end(), u.data(), u.data() + u.size());
      mail_.send_all({OutgoingMessage{
          make_reduction_message(static_cast<int>(self_), 0, kInterfaceSolution, sent), true, {}}});
    }
    if (!interface_->ready()) return std::nullopt;  // every agent alike: the same Sigma
  }
  const Eigen::MatrixXd x = interface_->back(y, u);
  for (Eigen::Index k = 0; k < m; ++k)
    poses_[own_[static_cast<std::size_t>(k)]].t = x.row(k).transpose();
  for (auto& [id, pose] : poses_) {
    if (slot.count(id) != 0) continue;
    const Eigen::Index row = interface_->team_row(id);
    if (row < 0)
      throw std::logic_error("rounding: neighbour pose " + std::to_string(id) +
                             " outside the team's interface");
    pose.t = u.row(row).transpose();
  }
  // The cost does not depend on a common shift: its share and pose 0's translation (its
  // owner's; the others add zeros, exactly) travel in one sum, in agent-id order.
  std::vector<double> mine_cost(static_cast<std::size_t>(1 + d), 0.0);
  mine_cost[0] = cost_share();
  if (local_.owner[0] == self_)
    for (Eigen::Index k = 0; k < d; ++k)
      mine_cost[static_cast<std::size_t>(1 + k)] = x(slot.at(0), k);
  const PoseBlockMessage cm =
      make_reduction_message(static_cast<int>(self_), 0, kInterfaceCost, mine_cost);
  mail_.send_all({OutgoingMessage{cm, true, {}}});
  auto sums = mail_.gather(kInterfaceCost, 0, others());
  std::vector<double> total(mine_cost.size(), 0.0);
  for (std::uint32_t a : everyone_) {
    const auto& v = a == self_ ? mine_cost : reduction_values(sums.at(a), mine_cost.size());
    for (std::size_t k = 0; k < total.size(); ++k) total[k] += v[k];
  }
  const Eigen::Map<const Eigen::VectorXd> t0(total.data() + 1, d);
  for (auto& [id, pose] : poses_) pose.t -= t0;
  return total[0];
}

}  // namespace tessera::agent
