#include "agent/distributed_rounding.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <string>
#include <variant>

#include "problem/lifting.hpp"

namespace tessera::agent {

RoundLoopResult DistributedRounding::run(RoundLoopResult res) {
  rotations();
  res.translation_iterations = translations();
  res.poses.clear();
  for (std::size_t s = 0; s < own_.size(); ++s) res.poses.push_back(poses_.at(own_[s]));
  res.cost = cost();
  return res;
}

double DistributedRounding::reduce(std::uint32_t phase, std::uint32_t round, double a, double b,
                                   double* b_sum) {
  RoundStatusMessage st;
  st.round = round;
  st.sender = self_;
  st.phase = phase;
  st.cost = a;
  st.grad_norm_sq = b;
  mail_.send_all({OutgoingMessage{st, true, {}}});
  auto got = mail_.gather(phase, round, others());
  double sa = 0.0, sb = 0.0;
  for (std::uint32_t k : everyone_) {  // agent-id order: bit-identical sums everywhere
    const RoundStatusMessage& m = k == self_ ? st : std::get<RoundStatusMessage>(got.at(k));
    sa += m.cost;
    sb += m.grad_norm_sq;
  }
  if (b_sum) *b_sum = sb;
  return sa;
}

std::vector<std::uint32_t> DistributedRounding::others() const {
  std::vector<std::uint32_t> o;
  for (auto a : everyone_)
    if (a != self_) o.push_back(a);
  return o;
}

template <class F>
std::map<std::size_t, std::vector<double>> DistributedRounding::exchange(std::uint32_t phase,
                                                                         std::uint32_t round,
                                                                         std::uint32_t rank,
                                                                         F values) {
  send_publics(phase, round, rank, values);
  return gather_publics(phase, round, rank);
}

template <class F>
void DistributedRounding::send_publics(std::uint32_t phase, std::uint32_t round, std::uint32_t rank,
                                       F values) {
  const std::size_t width = width_of(rank);
  const auto& adj = layout_.adjacent[self_];
  for (std::size_t k = 0; k < adj.size(); ++k) {
    PoseBlockMessage m;
    m.round = round;
    m.sender = self_;
    m.phase = phase;
    m.rank = rank;
    m.dim = static_cast<std::uint32_t>(d_);
    for (std::size_t id : layout_.public_to[self_][k]) {
      m.pose_ids.push_back(static_cast<std::uint32_t>(id));
      std::vector<double> v = values(id);
      v.resize(width, 0.0);
      m.data.insert(m.data.end(), v.begin(), v.end());
    }
    mail_.send_all({OutgoingMessage{m, false, {static_cast<std::uint32_t>(adj[k])}}});
  }
}

std::map<std::size_t, std::vector<double>> DistributedRounding::gather_publics(std::uint32_t phase,
                                                                               std::uint32_t round,
                                                                               std::uint32_t rank) {
  const std::size_t width = width_of(rank);
  std::map<std::size_t, std::vector<double>> out;
  for (auto& [sender, msg] : mail_.gather(phase, round, neighbours_)) {
    const auto& m = std::get<PoseBlockMessage>(msg);
    if (m.data.size() != m.pose_ids.size() * width)
      throw std::runtime_error("rounding: block of the wrong size from agent " +
                               std::to_string(sender));
    for (std::size_t k = 0; k < m.pose_ids.size(); ++k)
      out[m.pose_ids[k]] = std::vector<double>(m.data.begin() + static_cast<long>(k * width),
                                               m.data.begin() + static_cast<long>((k + 1) * width));
  }
  return out;
}

void DistributedRounding::rotations() {
  const Eigen::Index r = Y_.rows(), d = d_, m = static_cast<Eigen::Index>(own_.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(r, r);
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto B = Y_.middleCols((d + 1) * i, d);
    G.noalias() += B * B.transpose();
  }
  // The Gram matrix travels as r "poses" of rank r whose first r entries are its columns.
  PoseBlockMessage gm;
  gm.sender = self_;
  gm.phase = kGram;
  gm.rank = static_cast<std::uint32_t>(r);
  gm.dim = static_cast<std::uint32_t>(d);
  for (Eigen::Index c = 0; c < r; ++c) {
    gm.pose_ids.push_back(static_cast<std::uint32_t>(c));
    for (Eigen::Index k = 0; k < r * (d + 1); ++k) gm.data.push_back(k < r ? G(k, c) : 0.0);
  }
  mail_.send_all({OutgoingMessage{gm, true, {}}});
  auto got = mail_.gather(kGram, 0, others());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(r, r);
  for (std::uint32_t a : everyone_) {
    if (a == self_) {
      S += G;
      continue;
    }
    const auto& msg = std::get<PoseBlockMessage>(got.at(a));
    if (msg.data.size() != static_cast<std::size_t>(r * r * (d + 1)))
      throw std::runtime_error("rounding: Gram matrix of the wrong size from agent " +
                               std::to_string(a));
    for (Eigen::Index c = 0; c < r; ++c)
      for (Eigen::Index k = 0; k < r; ++k)
        S(k, c) += msg.data[static_cast<std::size_t>(c * r * (d + 1) + k)];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  const Eigen::MatrixXd U = eig.eigenvectors().rightCols(d);
  Eigen::MatrixXd R(d, d * m);
  double negative = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    R.middleCols(d * i, d) = U.transpose() * Y_.middleCols((d + 1) * i, d);
    if (R.middleCols(d * i, d).determinant() < 0) negative += 1;
  }
  const double total_negative = reduce(kNegative, 0, negative, 0.0, nullptr);
  const double n = static_cast<double>(local_.num_poses);
  for (Eigen::Index i = 0; i < m; ++i) {
    Eigen::MatrixXd Ri = R.middleCols(d * i, d);
    if (2 * total_negative > n) Ri.row(d - 1) *= -1.0;
    poses_[own_[static_cast<std::size_t>(i)]] =
        Pose{project_to_rotation(Ri), Eigen::VectorXd::Zero(d)};
  }
  auto nb = exchange(kRotations, 0, static_cast<std::uint32_t>(d), [&](std::size_t id) {
    const Pose& p = poses_.at(id);
    return std::vector<double>(p.R.data(), p.R.data() + d * d);
  });
  for (auto& [id, v] : nb)
    poses_[id] = Pose{Eigen::Map<const Eigen::MatrixXd>(v.data(), d, d), Eigen::VectorXd::Zero(d)};
}

std::uint32_t DistributedRounding::translations() {
  const Eigen::Index d = d_, m = static_cast<Eigen::Index>(own_.size());
  std::map<std::size_t, Eigen::Index> slot;
  for (Eigen::Index s = 0; s < m; ++s) slot[own_[static_cast<std::size_t>(s)]] = s;
  auto free = [&](std::size_t id) { return id != 0; };
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(m, d);
  std::vector<Eigen::Triplet<double>> trip;
  for (Eigen::Index s = 0; s < m; ++s)
    if (!free(own_[static_cast<std::size_t>(s)])) trip.emplace_back(s, s, 1.0);  // fixed at 0
  for (const Measurement& e : local_.measurements) {
    const Eigen::VectorXd c = poses_.at(e.i).R * e.t;
    auto si = slot.find(e.i), sj = slot.find(e.j);
    const bool oi = si != slot.end() && free(e.i), oj = sj != slot.end() && free(e.j);
    if (oi) {
      b.row(si->second) -= e.tau * c.transpose();
      trip.emplace_back(si->second, si->second, e.tau);
    }
    if (oj) {
      b.row(sj->second) += e.tau * c.transpose();
      trip.emplace_back(sj->second, sj->second, e.tau);
    }
    if (oi && oj) {
      trip.emplace_back(si->second, sj->second, -e.tau);
      trip.emplace_back(sj->second, si->second, -e.tau);
    }
  }
  Eigen::SparseMatrix<double> Lbb(m, m);
  Lbb.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> chol(Lbb);
  if (chol.info() != Eigen::Success)
    throw std::runtime_error("rounding: local translation Laplacian is singular");
  auto precondition = [&](const Eigen::MatrixXd& r) {
    Eigen::MatrixXd z = chol.solve(r);
    for (Eigen::Index s = 0; s < m; ++s)
      if (!free(own_[static_cast<std::size_t>(s)])) z.row(s).setZero();
    return z;
  };
  // L p for owned rows, given p on owned poses and the neighbours' public entries.
  auto apply = [&](const Eigen::MatrixXd& p, const std::map<std::size_t, std::vector<double>>& pn) {
    auto value = [&](std::size_t id) -> Eigen::VectorXd {
      if (!free(id)) return Eigen::VectorXd::Zero(d);
      auto s = slot.find(id);
      if (s != slot.end()) return p.row(s->second).transpose();
      const auto& v = pn.at(id);
      return Eigen::Map<const Eigen::VectorXd>(v.data(), d);
    };
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m, d);
    for (const Measurement& e : local_.measurements) {
      const Eigen::VectorXd diff = e.tau * (value(e.j) - value(e.i));
      auto si = slot.find(e.i), sj = slot.find(e.j);
      if (si != slot.end() && free(e.i)) out.row(si->second) -= diff.transpose();
      if (sj != slot.end() && free(e.j)) out.row(sj->second) += diff.transpose();
    }
    return out;
  };
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(m, d), r = b;
  Eigen::MatrixXd z = precondition(r), p = z;
  // Each residual step also carries the public entries of z and x to the neighbours (as a
  // rank-2 block: z, then x). With z and the new beta every agent forms its neighbours'
  // public search direction itself (p = z + beta p, the owner's formula), so the direction
  // needs no step of its own, and the x of the last step are the final translations: an
  // iteration costs two message steps (curvature, residual) instead of three.
  auto send_zx = [&](std::uint32_t round) {
    send_publics(kDirection, round, 2, [&](std::size_t id) {
      const Eigen::Index s = slot.at(id);
      std::vector<double> v(2 * static_cast<std::size_t>(d));
      for (Eigen::Index k = 0; k < d; ++k) {
        v[static_cast<std::size_t>(k)] = z(s, k);
        v[static_cast<std::size_t>(d + k)] = x(s, k);
      }
      return v;
    });
  };
  std::map<std::size_t, std::vector<double>> zx;  // neighbours' public z and x
  std::map<std::size_t, std::vector<double>> pn;  // neighbours' public p (first d entries)
  send_zx(0);
  double rr0 = 0.0;
  double rz = reduce(kInitialResidual, 0, (r.array() * z.array()).sum(), r.squaredNorm(), &rr0);
  zx = gather_publics(kDirection, 0, 2);
  for (const auto& [id, v] : zx) pn[id] = std::vector<double>(v.begin(), v.begin() + d);
  const double tol = 1e-24 * rr0;  // relative residual 1e-12
  const std::uint32_t max_it = 5000;
  std::uint32_t it = 0;
  double rr = rr0;
  while (rr > tol && it < max_it && rr0 > 0) {
    const Eigen::MatrixXd Ap = apply(p, pn);
    const double pAp = reduce(kCurvature, it, (p.array() * Ap.array()).sum(), 0.0, nullptr);
    if (!(pAp > 0)) break;
    const double alpha = rz / pAp;
    x += alpha * p;
    r -= alpha * Ap;
    z = precondition(r);
    send_zx(it + 1);
    const double rz_new =
        reduce(kResidual, it, (r.array() * z.array()).sum(), r.squaredNorm(), &rr);
    zx = gather_publics(kDirection, it + 1, 2);
    const double beta = rz_new / rz;
    p = z + beta * p;
    for (const auto& [id, v] : zx) {
      std::vector<double>& q = pn.at(id);
      for (Eigen::Index k = 0; k < d; ++k)
        q[static_cast<std::size_t>(k)] =
            v[static_cast<std::size_t>(k)] + beta * q[static_cast<std::size_t>(k)];
    }
    rz = rz_new;
    ++it;
  }
  for (Eigen::Index s = 0; s < m; ++s)
    poses_[own_[static_cast<std::size_t>(s)]].t = x.row(s).transpose();
  for (const auto& [id, v] : zx)  // the x sent with the last residual (or initial) step
    poses_[id].t = Eigen::Map<const Eigen::VectorXd>(v.data() + d, d);
  return it;
}

double DistributedRounding::cost() {
  double share = 0.0;
  for (const Measurement& e : local_.measurements) {
    const Pose& a = poses_.at(e.i);
    const Pose& b = poses_.at(e.j);
    const double f =
        e.kappa * (b.R - a.R * e.R).squaredNorm() + e.tau * (b.t - a.t - a.R * e.t).squaredNorm();
    const bool both = local_.owner[e.i] == self_ && local_.owner[e.j] == self_;
    share += both ? f : 0.5 * f;
  }
  return reduce(kCost, 0, share, 0.0, nullptr);
}

}  // namespace tessera::agent
