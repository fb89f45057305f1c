#include "runtime/distributed_rounding.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>
#include <variant>

#include "distributed/translation_interface_solve.hpp"
#include "runtime/rounding_coarse.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera::agent {

void DistributedRoundingOptions::validate() const {
  if (!(settle_tolerance >= 0.0 && settle_tolerance <= 1e-6))
    throw InputError("DistributedRoundingOptions::settle_tolerance must be in [0, 1e-6], got " +
                     std::to_string(settle_tolerance));
  if (settle_window < 1 || settle_window > 1000)
    throw InputError("DistributedRoundingOptions::settle_window must be in [1, 1000], got " +
                     std::to_string(settle_window));
  if (interface_max_poses > 1000000)
    throw InputError(
        "DistributedRoundingOptions::interface_max_poses must be in [0, 1000000], got " +
        std::to_string(interface_max_poses));
  if (interface_one_factor_min_poses > 1000000)
    throw InputError(
        "DistributedRoundingOptions::interface_one_factor_min_poses must be in [0, 1000000], got " +
        std::to_string(interface_one_factor_min_poses));
}

DistributedRounding::~DistributedRounding() = default;

RoundLoopResult DistributedRounding::run(RoundLoopResult res) {
  rotations();
  std::optional<double> exact;
  if (take_interface_shares()) exact = interface_translations();
  if (exact) {
    res.translation_iterations = 0;
    res.rounding_interface_poses = static_cast<std::uint32_t>(interface_->team_size());
    res.cost = *exact;
  } else {
    interface_.reset();
    res.translation_iterations = translations(res.relaxation_cost);
    res.rounding_interface_poses = 0;
    res.cost = cost();
  }
  res.poses.clear();
  for (std::size_t s = 0; s < own_.size(); ++s) res.poses.push_back(poses_.at(own_[s]));
  return res;
}

double DistributedRounding::reduce(std::uint32_t phase, std::uint32_t round, double a, double b,
                                   double* b_sum, double c, double* c_sum) {
  RoundStatusMessage st;
  st.round = round;
  st.sender = self_;
  st.phase = phase;
  st.cost = a;
  st.grad_norm_sq = b;
  st.block_grad_norm = c;
  mail_.send_all({OutgoingMessage{st, true, {}}});
  auto got = mail_.gather(phase, round, others());
  double sa = 0.0, sb = 0.0, sc = 0.0;
  for (std::uint32_t k : everyone_) {  // agent-id order: bit-identical sums everywhere
    const RoundStatusMessage& m = k == self_ ? st : std::get<RoundStatusMessage>(got.at(k));
    sa += m.cost;
    sb += m.grad_norm_sq;
    sc += m.block_grad_norm;
  }
  if (b_sum) *b_sum = sb;
  if (c_sum) *c_sum = sc;
  return sa;
}

std::vector<std::uint32_t> DistributedRounding::others() const {
  std::vector<std::uint32_t> o;
  for (auto a : everyone_)
    if (a != self_) o.push_back(a);
  return o;
}

PoseBlockMessage DistributedRounding::block_message(std::uint32_t phase, std::uint32_t round,
                                                    std::uint32_t rank) const {
  PoseBlockMessage m;
  m.round = round;
  m.sender = self_;
  m.phase = phase;
  m.rank = rank;
  m.dim = static_cast<std::uint32_t>(d_);
  return m;
}

double* DistributedRounding::add_entry(PoseBlockMessage& m, std::uint32_t id) const {
  m.pose_ids.push_back(id);
  m.data.resize(m.data.size() + width_of(m.rank), 0.0);
  return m.data.data() + m.data.size() - width_of(m.rank);
}

template <class F>
void DistributedRounding::for_each_entry(const PoseBlockMessage& mine, const char* what, F f) {
  const std::size_t width = width_of(mine.rank);
  auto got = mail_.gather(mine.phase, mine.round, others());
  for (std::uint32_t a : everyone_) {  // agent-id order: bit-identical sums everywhere
    const PoseBlockMessage& m = a == self_ ? mine : std::get<PoseBlockMessage>(got.at(a));
    if (m.data.size() != m.pose_ids.size() * width)
      throw std::runtime_error(std::string("rounding: ") + what + " of the wrong size from agent " +
                               std::to_string(a));
    for (std::size_t e = 0; e < m.pose_ids.size(); ++e)
      f(a, m.pose_ids[e], m.data.data() + e * width);
  }
}

DistributedRounding::CoarseSums DistributedRounding::coarse_reduce(
    std::uint32_t round, const double (&scalars)[3], const Eigen::MatrixXd& coupling,
    const Eigen::RowVectorXd& own, const std::vector<std::uint32_t>& touched) {
  // Entry k < N of the message: this agent's coupling row k, then (k = self) its own sum;
  // entry N: the scalars.
  const auto N = static_cast<std::uint32_t>(everyone_.size());
  const Eigen::Index d = d_;
  PoseBlockMessage msg = block_message(kCoarseSums, round, 2);
  for (std::uint32_t k : touched) {
    double* v = add_entry(msg, k);
    for (Eigen::Index j = 0; j < d; ++j) {
      v[j] = coupling(static_cast<Eigen::Index>(k), j);
      if (k == self_) v[d + j] = own(j);
    }
  }
  std::copy(scalars, scalars + 3, add_entry(msg, N));
  mail_.send_all({OutgoingMessage{msg, true, {}}});
  CoarseSums out;
  out.V = Eigen::MatrixXd::Zero(N, d);
  out.S = Eigen::MatrixXd::Zero(N, d);
  for_each_entry(msg, "coarse sums", [&](std::uint32_t a, std::uint32_t k, const double* v) {
    if (k > N)
      throw std::runtime_error("rounding: coarse sums for block " + std::to_string(k) +
                               " from agent " + std::to_string(a));
    if (k == N) {
      out.a += v[0];
      out.b += v[1];
      out.c += v[2];
      return;
    }
    for (Eigen::Index j = 0; j < d; ++j) {
      out.V(static_cast<Eigen::Index>(k), j) += v[j];
      if (k == a) out.S(static_cast<Eigen::Index>(k), j) = v[d + j];
    }
  });
  return out;
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
    PoseBlockMessage m = block_message(phase, round, rank);
    for (std::size_t id : layout_.public_to[self_][k]) {
      const std::vector<double> v = values(id);
      std::copy_n(v.begin(), std::min(v.size(), width),
                  add_entry(m, static_cast<std::uint32_t>(id)));
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
  PoseBlockMessage gm = block_message(kGram, 0, static_cast<std::uint32_t>(r));
  for (Eigen::Index c = 0; c < r; ++c)
    std::copy_n(G.col(c).data(), r, add_entry(gm, static_cast<std::uint32_t>(c)));
  mail_.send_all({OutgoingMessage{gm, true, {}}});
  send_interface_share();  // the translation Laplacian does not depend on the rotations
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
  frame_ = eig.eigenvectors().rightCols(d);
  const Eigen::MatrixXd& U = frame_;
  Eigen::MatrixXd R(d, d * m);
  double negative = 0;
  // d x d blocks on the stack (d <= 3): no heap traffic per pose.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> Ri(d, d);
  for (Eigen::Index i = 0; i < m; ++i) {
    R.middleCols(d * i, d) = U.transpose() * Y_.middleCols((d + 1) * i, d);
    if (determinant_of(R.middleCols(d * i, d)) < 0) negative += 1;
  }
  const double total_negative = reduce(kNegative, 0, negative, 0.0, nullptr);
  const double n = static_cast<double>(local_.num_poses);
  reflected_ = 2 * total_negative > n;
  for (Eigen::Index i = 0; i < m; ++i) {
    Ri = R.middleCols(d * i, d);
    if (reflected_) Ri.row(d - 1) *= -1.0;
    Pose& p = poses_[own_[static_cast<std::size_t>(i)]];
    p.R.resize(d, d);
    project_to_rotation(Ri, p.R);
    p.t = Eigen::VectorXd::Zero(d);
  }
  auto nb = exchange(kRotations, 0, static_cast<std::uint32_t>(d), [&](std::size_t id) {
    const Pose& p = poses_.at(id);
    return std::vector<double>(p.R.data(), p.R.data() + d * d);
  });
  for (auto& [id, v] : nb)
    poses_[id] = Pose{Eigen::Map<const Eigen::MatrixXd>(v.data(), d, d), Eigen::VectorXd::Zero(d)};
}

Eigen::MatrixXd DistributedRounding::warm_start() {
  // The iterate's own translations in the rounded frame (U^T y_i, reflected as the rotations
  // were), shifted so that pose 0 sits at the origin as the solve fixes it. Pose 0's owner
  // gives its translation through a sum to which every other agent adds zeros (exact).
  const Eigen::Index d = d_, m = static_cast<Eigen::Index>(own_.size());
  Eigen::MatrixXd x(m, d);
  for (Eigen::Index i = 0; i < m; ++i)
    x.row(i) = (frame_.transpose() * Y_.col((d + 1) * i + d)).transpose();
  if (reflected_) x.col(d - 1) *= -1.0;
  double t0[3] = {0.0, 0.0, 0.0};
  if (local_.owner[0] == self_)
    for (Eigen::Index i = 0; i < m; ++i)
      if (own_[static_cast<std::size_t>(i)] == 0)
        for (Eigen::Index k = 0; k < d; ++k) t0[k] = x(i, k);
  t0[0] = reduce(kWarmStartAnchor, 0, t0[0], t0[1], &t0[1], t0[2], &t0[2]);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index k = 0; k < d; ++k) x(i, k) -= t0[k];
  return x;
}

std::uint32_t DistributedRounding::translations(double relaxation_cost) {
  const Eigen::Index d = d_, m = static_cast<Eigen::Index>(own_.size());
  std::map<std::size_t, Eigen::Index> slot;
  for (Eigen::Index s = 0; s < m; ++s) slot[own_[static_cast<std::size_t>(s)]] = s;
  auto free = [&](std::size_t id) { return id != 0; };
  // The neighbours' public poses this agent's measurements read, as columns of L_nb.
  std::map<std::size_t, Eigen::Index> nb_slot;
  std::vector<std::size_t> nb_ids;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(m, d);
  std::vector<Eigen::Triplet<double>> trip, trip_nb;
  auto column_of = [&](std::size_t id) {
    auto [it, added] = nb_slot.emplace(id, static_cast<Eigen::Index>(nb_ids.size()));
    if (added) nb_ids.push_back(id);
    return it->second;
  };
  for (const Measurement& e : local_.measurements) {
    const Eigen::VectorXd c = poses_.at(e.i).R * e.t;
    auto si = slot.find(e.i), sj = slot.find(e.j);
    const bool oi = si != slot.end() && free(e.i), oj = sj != slot.end() && free(e.j);
    if (oi) {
      b.row(si->second) -= e.tau * c.transpose();
      trip.emplace_back(si->second, si->second, e.tau);
      if (oj)
        trip.emplace_back(si->second, sj->second, -e.tau);
      else if (sj == slot.end() && free(e.j))
        trip_nb.emplace_back(si->second, column_of(e.j), -e.tau);
    }
    if (oj) {
      b.row(sj->second) += e.tau * c.transpose();
      trip.emplace_back(sj->second, sj->second, e.tau);
      if (oi)
        trip.emplace_back(sj->second, si->second, -e.tau);
      else if (si == slot.end() && free(e.i))
        trip_nb.emplace_back(sj->second, column_of(e.i), -e.tau);
    }
  }
  // L's rows of the free owned poses: L_own on the owned columns, L_nb on the neighbours'.
  Eigen::SparseMatrix<double> L_own(m, m), L_nb(m, static_cast<Eigen::Index>(nb_ids.size()));
  L_own.setFromTriplets(trip.begin(), trip.end());
  L_nb.setFromTriplets(trip_nb.begin(), trip_nb.end());
  for (Eigen::Index s = 0; s < m; ++s)
    if (!free(own_[static_cast<std::size_t>(s)])) trip.emplace_back(s, s, 1.0);  // fixed at 0
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
  // L p for owned rows, given p on owned poses and the neighbours' public entries (the
  // first d of each), as two sparse products (index maps built once, not per product).
  auto apply = [&](const Eigen::MatrixXd& p, const std::map<std::size_t, std::vector<double>>& pn) {
    Eigen::MatrixXd P(static_cast<Eigen::Index>(nb_ids.size()), d);
    for (std::size_t k = 0; k < nb_ids.size(); ++k) {
      auto v = pn.find(nb_ids[k]);
      if (v == pn.end())
        throw std::runtime_error("rounding: no value for pose " + std::to_string(nb_ids[k]) +
                                 " from its owner");
      P.row(static_cast<Eigen::Index>(k)) =
          Eigen::Map<const Eigen::RowVectorXd>(v->second.data(), d);
    }
    Eigen::MatrixXd out = L_own * p;
    out.noalias() += L_nb * P;
    return out;
  };
  // The public rows of `a` (and of `b2` after them) for send_publics.
  auto rows_of = [&slot, d](const Eigen::MatrixXd* a, const Eigen::MatrixXd* b2) {
    return [a, b2, &slot, d](std::size_t id) {
      const Eigen::Index row = slot.at(id);
      std::vector<double> v(static_cast<std::size_t>(b2 ? 2 * d : d));
      for (Eigen::Index k = 0; k < d; ++k) {
        v[static_cast<std::size_t>(k)] = (*a)(row, k);
        if (b2) v[static_cast<std::size_t>(d + k)] = (*b2)(row, k);
      }
      return v;
    };
  };
  // Warm start: near a critical point the rounded rotations are the iterate's up to a small
  // projection, so the iterate's translations are close to the optimal ones; from x = 0 the
  // solve first has to build the whole map (a 1M-pose grid: hundreds of all-agent steps more).
  // One message step: the neighbours' start and |b|^2 (the residual stop stays relative to b).
  Eigen::MatrixXd x = options_.warm_start ? warm_start() : Eigen::MatrixXd::Zero(m, d);
  // The coarse level's rows of E travel in the same message step (sent before, gathered after).
  const auto N = static_cast<std::uint32_t>(everyone_.size());
  std::optional<RoundingCoarse> coarse;
  PoseBlockMessage erow = block_message(kCoarseMatrix, 0, 1);
  if (options_.coarse_correction && N > 1) {
    std::vector<std::uint32_t> nb_block;
    for (std::size_t id : nb_ids) nb_block.push_back(local_.owner[id]);
    std::vector<bool> free_row(static_cast<std::size_t>(m));
    for (Eigen::Index k = 0; k < m; ++k)
      free_row[static_cast<std::size_t>(k)] = free(own_[static_cast<std::size_t>(k)]);
    coarse.emplace(L_own, L_nb, nb_block, free_row, self_, N);
    const Eigen::VectorXd row = coarse->own_row();
    for (std::uint32_t k : coarse->touched())
      *add_entry(erow, k) = row(static_cast<Eigen::Index>(k));
    mail_.send_all({OutgoingMessage{erow, true, {}}});
  }
  send_publics(kWarmStartValues, 0, 1, rows_of(&x, nullptr));
  double bb = reduce(kWarmStartNorm, 0, b.squaredNorm(), 0.0, nullptr);
  if (coarse) {
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(N, N);
    for_each_entry(erow, "coarse row", [&](std::uint32_t a, std::uint32_t k, const double* v) {
      if (k >= N)
        throw std::runtime_error("rounding: coarse row entry " + std::to_string(k) +
                                 " from agent " + std::to_string(a));
      E(a, k) = v[0];
    });
    if (!coarse->factorise(E)) coarse.reset();  // the same E everywhere: all agents agree
  }
  Eigen::MatrixXd r = b - apply(x, gather_publics(kWarmStartValues, 0, 1));
  // Pipelined PCG (Ghysels & Vanroose, "Hiding global synchronization latency in the
  // preconditioned conjugate gradient algorithm", 2014): PCG's iterates in exact arithmetic,
  // with w = L u, s = L p, q = M s and n = L q carried by recurrences, so that an iteration's
  // two inner products (and |r|^2 for the stop) and the one product with L it needs,
  // n = L M w, are independent: the reduction and the neighbours' public entries of M w
  // travel in ONE message step per iteration. Plain PCG needs two (<p, L p>, then <r, z>
  // with the new z's public entries): intel's rounding took 105 message steps, ~0.85 ms each
  // on 2 cores, 62 this way (docs/dds-runtime.md, "The rounding's message steps"). Each step also
  // carries x's public entries, so the last one gives the neighbours' final translations.
  //
  // Two stops, whichever comes first (every agent sees the same sums, so all stop together):
  // - the residual computed from x is below 1e-12 of b's (the exact solve to rounding error);
  // - the cost is settled: the translation part of the rounded cost is t^T L t - 2 b^T t + c,
  //   and a CG step lowers it by exactly alpha <r, M r>, so the sum of those over the last
  //   settle_window steps estimates what the rest of the solve could still remove (Strakos and
  //   Tichy's estimate of the error in the L-norm, which is that excess cost). It stops when
  //   that is below settle_tolerance * max(1, f(X)) (DistributedRoundingOptions says why 1e-10).
  Eigen::MatrixXd u, w, p, s, q, n_rec;
  // With the coarse level: cw = Z^T w (every block's sum of w, known to every agent) and
  // zc = Z^T n_rec, carried like w and n_rec; cw is reset each step to the sums just gathered
  // (the step's Z^T w), so it drifts by one step's rounding at most.
  Eigen::MatrixXd cw, zc;
  const std::uint32_t max_it = 5000;
  std::uint32_t it = 0, step = 1, restarts = 0;
  const double tol = 1e-24 * bb,
               settle = options_.settle_tolerance * std::max(1.0, relaxation_cost);
  double gamma_old = 0.0, alpha_old = 0.0;
  std::vector<double> decreases;  // alpha * gamma of every step taken
  // Whether r is b - L x as computed (a start), not as the recurrences carried it.
  bool fresh = true;
  std::map<std::size_t, std::vector<double>> mx;  // neighbours' public M w and x
  // (Re)starts from x with r = b - L x: one message step for w = L u.
  auto start = [&] {
    u = precondition(r);
    if (coarse) {  // u = B r + Z E^-1 Z^T r needs Z^T r first: one more message step
      const double none[3] = {0.0, 0.0, 0.0};
      const CoarseSums cs = coarse_reduce(step, none, coarse->coupling_sums(u),
                                          coarse->block_sum(r), coarse->touched());
      ++step;
      const Eigen::MatrixXd y = coarse->solve(cs.S);
      coarse->add_offset(u, y);
      cw = cs.V + coarse->times(y);  // Z^T L u = Z^T L B r + E y
      zc = Eigen::MatrixXd::Zero(N, d);
    }
    send_publics(kDirection, step, 1, rows_of(&u, nullptr));
    w = apply(u, gather_publics(kDirection, step, 1));
    ++step;
    p = Eigen::MatrixXd::Zero(m, d);
    s = p;
    q = p;
    n_rec = p;
    fresh = true;
  };
  start();
  for (;;) {
    Eigen::MatrixXd mw = precondition(w), y, zn, cw_now, coupling_Bw;
    if (coarse) {
      coupling_Bw = coarse->coupling_sums(mw);  // of B w, before the offset makes it M w
      y = coarse->solve(cw);
      coarse->add_offset(mw, y);
    }
    send_publics(kDirection, step, 2, rows_of(&mw, &x));
    double gamma = 0.0, delta = 0.0, rr = 0.0;
    if (coarse) {
      const double sc[3] = {frobenius_inner(r, u), frobenius_inner(w, u), r.squaredNorm()};
      const CoarseSums cs =
          coarse_reduce(step, sc, coupling_Bw, coarse->block_sum(w), coarse->touched());
      gamma = cs.a;
      delta = cs.b;
      rr = cs.c;
      zn = cs.V + coarse->times(y);  // Z^T L M w = Z^T L B w + E y
      cw_now = cs.S;
    } else {
      gamma = reduce(kResidual, step, frobenius_inner(r, u), frobenius_inner(w, u), &delta,
                     r.squaredNorm(), &rr);
    }
    mx = gather_publics(kDirection, step, 2);
    ++step;
    double left = 0.0;  // cost removed by the last settle_window steps
    for (std::size_t k = decreases.size() - std::min(decreases.size(), options_.settle_window);
         k < decreases.size(); ++k)
      left += decreases[k];
    mail_.report_progress(ProgressStage::kRounding, it, left);
    // x and the neighbours' x (in mx) are the same step's here.
    if (settle > 0 && decreases.size() >= options_.settle_window && left <= settle) break;
    const double beta = fresh ? 0.0 : gamma / gamma_old;
    const double pAp = fresh ? delta : delta - beta * gamma / alpha_old;  // <p, L p>
    if (!(rr > tol) || !(pAp > 0)) {
      // The recurrences drift from b - L x (more than plain PCG's), and <p, L p> from them
      // may lose its sign: the stop counts only for a residual computed from x. Otherwise
      // start again from x with that residual (the neighbours' x came with this step).
      // kitti_02 stopped on the recurrence's residual: 5.7e-9 of b's instead of 1e-12, 3e-6 m
      // off the direct solve; restarted (twice, on every graph measured): 1e-12, 1.3e-8 m as
      // plain PCG. A start whose <p, L p> is not positive ends the solve, as plain PCG's did.
      if (fresh || restarts >= kMaxRestarts) break;
      std::map<std::size_t, std::vector<double>> xn;
      for (const auto& [id, v] : mx) xn[id] = std::vector<double>(v.begin() + d, v.begin() + 2 * d);
      r = b - apply(x, xn);
      ++restarts;
      start();
      continue;
    }
    if (it >= max_it) break;
    const double alpha = gamma / pAp;
    const Eigen::MatrixXd n = apply(mw, mx);  // L M w
    n_rec = n + beta * n_rec;
    q = mw + beta * q;
    s = w + beta * s;
    p = u + beta * p;
    x += alpha * p;
    r -= alpha * s;
    u -= alpha * q;
    w -= alpha * n_rec;
    if (coarse) {
      zc = zn + beta * zc;
      cw = cw_now - alpha * zc;
    }
    gamma_old = gamma;
    alpha_old = alpha;
    decreases.push_back(alpha * gamma);
    fresh = false;
    ++it;
  }
  for (Eigen::Index k = 0; k < m; ++k)
    poses_[own_[static_cast<std::size_t>(k)]].t = x.row(k).transpose();
  for (const auto& [id, v] : mx)  // the x sent with the last step
    poses_[id].t = Eigen::Map<const Eigen::VectorXd>(v.data() + d, d);
  return it;
}

double DistributedRounding::cost() {
  return reduce(kCost, 0, cost_share(), 0.0, nullptr);
}

double DistributedRounding::cost_share() const {
  double share = 0.0;
  for (const Measurement& e : local_.measurements) {
    const Pose& a = poses_.at(e.i);
    const Pose& b = poses_.at(e.j);
    const double f =
        e.kappa * (b.R - a.R * e.R).squaredNorm() + e.tau * (b.t - a.t - a.R * e.t).squaredNorm();
    const bool both = local_.owner[e.i] == self_ && local_.owner[e.j] == self_;
    share += both ? f : 0.5 * f;
  }
  return share;
}

}  // namespace tessera::agent
