#include "agent/round_loop.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <tuple>
#include <variant>

#include "distributed/agent_factory.hpp"
#include "distributed/agent_state.hpp"
#include "distributed/block_layout.hpp"
#include "distributed/certified_agent.hpp"
#include "distributed/distributed_solver.hpp"
#include "distributed/in_process_driver.hpp"
#include "distributed/protocol_snapshot.hpp"
#include "distributed/round_protocol.hpp"
#include "distributed/stage_tag.hpp"
#include "problem/lifting.hpp"

namespace tessera::agent {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Phases of the rounding messages (statuses and pose blocks), after core's protocol.
enum RoundingPhase : std::uint32_t {
  kGram = kRoundingPhaseBase,  // r x r Gram matrix of the block's rotation parts
  kNegative,                   // number of rounded blocks with det < 0
  kRotations,                  // rounded rotations of public poses
  kInitialResidual,            // PCG: <r,z>, <r,r> at the start
  kDirection,                  // PCG: public entries of the search direction
  kCurvature,                  // PCG: <p, L p>
  kResidual,                   // PCG: <r,z>, <r,r> after a step
  kTranslations,               // retired: the final translations ride on the last CG step
  kCost,                       // cost share of the rounded poses
  kTraffic                     // certificate and escape bytes sent (certification only)
};

DistributedOptions options_of(const RunOptions& o) {
  DistributedOptions opt;
  if (!o.algorithm.empty()) opt.algorithm = parse_algorithm(o.algorithm);
  if (o.rank > 0) opt.rank = static_cast<int>(o.rank);
  if (o.max_rounds > 0) opt.max_rounds = static_cast<int>(o.max_rounds);
  if (o.grad_norm_tolerance > 0) opt.grad_norm_tol = o.grad_norm_tolerance;
  opt.rel_cost_decrease_tol = o.relative_cost_tolerance;
  opt.seed = o.seed;
  opt.certify = o.certify;
  opt.validate();
  return opt;
}

// Delivers messages to core's protocol and keeps the rounding messages (which a faster agent
// may send before this one has finished) until the rounding asks for them.
class Mailbox {
 public:
  Mailbox(ProtocolChannel& channel, double timeout_s, std::uint32_t self)
      : channel_(channel), timeout_s_(timeout_s), self_(self) {}

  void send_all(const std::vector<OutgoingMessage>& out) {
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& m : out) {
      channel_.send(m);
      // Certificate and escape traffic, as the in-process driver counts it (per delivery).
      const std::uint32_t phase = phase_of(m.message);
      if (is_auxiliary_phase(phase)) continue;
      const StageKind kind = stage_kind(stage_of_phase(phase));
      if (kind == StageKind::kSolve) continue;
      const std::uint64_t copies = m.broadcast ? num_agents_ - 1 : m.recipients.size();
      (kind == StageKind::kCertify ? certificate_bytes : escape_bytes) +=
          copies * message_bytes(m.message);
    }
    send_s += seconds_since(t0);
    sent_since_gather_ = true;
  }

  // A message from the channel, its wait timed.
  std::optional<ProtocolMessage> receive() {
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<ProtocolMessage> msg = channel_.receive(timeout_s_);
    wait_s += seconds_since(t0);
    return msg;
  }

  void set_num_agents(std::uint32_t n) { num_agents_ = n; }

  // `describe` names where the agent is, for the timeout message.
  template <class Describe>
  void run_protocol(AgentProcess& protocol, std::vector<OutgoingMessage> first, Describe describe) {
    send_all(first);
    while (!protocol.done()) {
      std::optional<ProtocolMessage> msg = receive();
      if (!msg)
        throw std::runtime_error("agent " + std::to_string(self_) + ": no message for " +
                                 std::to_string(timeout_s_) + " s in " + describe());
      if (is_auxiliary_phase(phase_of(*msg))) {
        keep(std::move(*msg));
        continue;
      }
      send_all(protocol.handle(*msg));
    }
  }

  // Waits for the messages of (phase, round) from every agent in `senders`; returns them by
  // sender (ascending, so reductions sum in agent-id order).
  std::map<std::uint32_t, ProtocolMessage> gather(std::uint32_t phase, std::uint32_t round,
                                                  const std::vector<std::uint32_t>& senders) {
    const auto key = std::make_pair(phase, round);
    for (;;) {
      auto& have = stash_[key];
      bool all = true;
      for (auto s : senders) all = all && have.count(s);
      if (all) break;
      std::optional<ProtocolMessage> msg = receive();
      if (!msg) {
        std::string who;
        for (auto s : senders)
          if (!stash_[key].count(s)) who += " " + std::to_string(s);
        throw std::runtime_error("agent " + std::to_string(self_) + ": rounding step " +
                                 std::to_string(phase) + " (iteration " + std::to_string(round) +
                                 "): nothing received for " + std::to_string(timeout_s_) +
                                 " s; waiting for agent(s)" + who);
      }
      if (!is_auxiliary_phase(phase_of(*msg))) continue;  // late protocol traffic
      keep(std::move(*msg));
    }
    auto out = std::move(stash_[key]);
    stash_.erase(key);
    if (sent_since_gather_) ++gathers;  // the first wait after sending: one message step
    sent_since_gather_ = false;
    return out;
  }

 private:
  static std::uint32_t phase_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.phase; }, m);
  }
  static std::uint32_t round_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.round; }, m);
  }
  static std::uint32_t sender_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.sender; }, m);
  }
  void keep(ProtocolMessage m) {
    if (phase_of(m) >= kFinalReportPhase) return;  // for the coordinator
    stash_[{phase_of(m), round_of(m)}][sender_of(m)] = std::move(m);
  }

  ProtocolChannel& channel_;
  double timeout_s_;
  std::uint32_t self_;
  std::uint32_t num_agents_ = 1;
  bool sent_since_gather_ = false;

 public:
  std::uint64_t certificate_bytes = 0, escape_bytes = 0;  // sent by this agent
  double wait_s = 0.0, send_s = 0.0;                      // time in receive() and in send_all()
  std::uint32_t gathers = 0;  // completed gather() steps (the rounding's message steps)

 private:
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::map<std::uint32_t, ProtocolMessage>>
      stash_;
};

// The distributed rounding: the same result as core's round_solution (rank-d truncation via
// the r x r Gram matrix, reflection by majority, per-block projection to SO(d), translations
// optimal for those rotations with pose 0 at the origin) up to floating-point summation order.
class Rounding {
 public:
  Rounding(const AgentLocalData& local, const BlockLayout& layout, const AgentState& state,
           Mailbox& mail)
      : local_(local),
        layout_(layout),
        mail_(mail),
        self_(local.agent_id),
        d_(local.d),
        own_(layout.poses[local.agent_id]),
        Y_(state.Y) {
    for (std::uint32_t a = 0; a < local.num_agents; ++a) everyone_.push_back(a);
    for (int b : layout.adjacent[self_]) neighbours_.push_back(static_cast<std::uint32_t>(b));
  }

  /// A global sum of (a, b) over the agents, in agent-id order.
  double sum_over_agents(std::uint32_t phase, double a, double b, double* b_sum) {
    return reduce(phase, 0, a, b, b_sum);
  }

  RoundLoopResult run(RoundLoopResult res) {
    rotations();
    res.translation_iterations = translations();
    res.poses.clear();
    for (std::size_t s = 0; s < own_.size(); ++s) res.poses.push_back(poses_.at(own_[s]));
    res.cost = cost();
    return res;
  }

 private:
  double reduce(std::uint32_t phase, std::uint32_t round, double a, double b, double* b_sum) {
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

  std::vector<std::uint32_t> others() const {
    std::vector<std::uint32_t> o;
    for (auto a : everyone_)
      if (a != self_) o.push_back(a);
    return o;
  }

  // Sends `values(id)` (width doubles per pose, as a block of the given rank) of the public
  // poses to each neighbour and returns the neighbours' values by pose id.
  template <class F>
  std::map<std::size_t, std::vector<double>> exchange(std::uint32_t phase, std::uint32_t round,
                                                      std::uint32_t rank, F values) {
    send_publics(phase, round, rank, values);
    return gather_publics(phase, round, rank);
  }

  // The two halves of exchange(), for steps that also carry a reduction: send, reduce,
  // then gather (one message step instead of two).
  template <class F>
  void send_publics(std::uint32_t phase, std::uint32_t round, std::uint32_t rank, F values) {
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

  std::map<std::size_t, std::vector<double>> gather_publics(std::uint32_t phase,
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
        out[m.pose_ids[k]] =
            std::vector<double>(m.data.begin() + static_cast<long>(k * width),
                                m.data.begin() + static_cast<long>((k + 1) * width));
    }
    return out;
  }

  std::size_t width_of(std::uint32_t rank) const {
    return static_cast<std::size_t>(rank) * static_cast<std::size_t>(d_ + 1);
  }

  void rotations() {
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
      poses_[id] =
          Pose{Eigen::Map<const Eigen::MatrixXd>(v.data(), d, d), Eigen::VectorXd::Zero(d)};
  }

  // Preconditioned CG on L t = b (the translation Laplacian without the anchor pose 0), with
  // each agent's own Laplacian block as the preconditioner (solved exactly by Cholesky).
  std::uint32_t translations() {
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
    auto apply = [&](const Eigen::MatrixXd& p,
                     const std::map<std::size_t, std::vector<double>>& pn) {
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

  // Cost of the rounded poses: internal measurements in full, cut ones half (as core's status).
  double cost() {
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

  const AgentLocalData& local_;
  const BlockLayout& layout_;
  Mailbox& mail_;
  std::uint32_t self_;
  int d_;
  const std::vector<std::size_t>& own_;
  const Eigen::MatrixXd& Y_;
  std::vector<std::uint32_t> everyone_, neighbours_;
  std::map<std::size_t, Pose> poses_;  // own and neighbours' rounded poses
};

}  // namespace

RoundLoopResult run_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                               double receive_timeout_s, const RoundLoopHooks& hooks) {
  const DistributedOptions options = options_of(local.options);
  const bool lifted = local.lifted_start.size() > 0;
  if (lifted &&
      (local.lifted_start.cols() != (local.d + 1) * static_cast<Eigen::Index>(local.owned.size()) ||
       local.lifted_start.rows() != options.rank))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": lifted starting point of the wrong shape");
  if (!lifted && local.initial.size() != local.owned.size())
    throw std::runtime_error("agent " + std::to_string(local.agent_id) + ": " +
                             std::to_string(local.initial.size()) + " initial poses for " +
                             std::to_string(local.owned.size()) +
                             " owned poses (run the initialisation stage first)");
  if (options.rank < local.d)
    throw std::runtime_error("rank " + std::to_string(options.rank) +
                             " is below d = " + std::to_string(local.d));

  // Every agent builds the same layout from the structure (endpoints only).
  std::vector<Measurement> skeleton(local.structure.size());
  for (std::size_t k = 0; k < skeleton.size(); ++k) {
    skeleton[k].i = local.structure[k].first;
    skeleton[k].j = local.structure[k].second;
  }
  const std::vector<int> assignment(local.owner.begin(), local.owner.end());
  const BlockLayout layout = make_block_layout(local.num_poses, skeleton, assignment);
  const auto& own = layout.poses[local.agent_id];
  if (own.size() != local.owned.size() || !std::equal(own.begin(), own.end(), local.owned.begin()))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": owned poses do not match the assignment");

  // Core's agent, configured as the in-process engine configures it.
  AgentState state(static_cast<int>(local.agent_id), local.d, layout, local.measurements,
                   lifted ? local.lifted_start : lift_poses(local.initial, options.rank));
  const double variables =
      static_cast<double>(options.rank) * (local.d + 1) * static_cast<double>(local.num_poses);
  const auto scheme = make_momentum_scheme(options, layout, variables);
  const RoundConfig config = make_round_config(options, scheme.get());
  Mailbox mail(channel, receive_timeout_s, local.agent_id);
  mail.set_num_agents(local.num_agents);
  RoundLoopResult res;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<CertifiedAgent> sequence;
  if (!options.certify) {
    RoundProtocol protocol(state, layout, config);
    if (hooks.on_round) protocol.set_round_observer(hooks.on_round);
    mail.run_protocol(
        protocol, hooks.resume_from ? protocol.resume(*hooks.resume_from) : protocol.start(),
        [&] { return "round " + std::to_string(protocol.rounds()) + " of the solve"; });
    res.rounds = static_cast<std::uint32_t>(protocol.rounds());
    res.restarts = static_cast<std::uint32_t>(protocol.restarts());
    res.stop_reason = protocol.stop_reason();
    if (!protocol.trace().empty()) {
      res.relaxation_cost = protocol.trace().back().cost;
      res.grad_norm = protocol.trace().back().grad_norm;
    }
  } else {
    // The certified sequence. Checkpoints and rollbacks cover its first solve stage.
    sequence = std::make_unique<CertifiedAgent>(state, layout, options);
    if (hooks.on_round) sequence->set_round_observer(hooks.on_round);
    mail.run_protocol(
        *sequence, hooks.resume_from ? sequence->resume(*hooks.resume_from) : sequence->start(),
        [&] { return "stage " + std::to_string(sequence->stage()) + " of the certified solve"; });
    const SolveStageRecord& last = sequence->solves().back();
    res.rounds = static_cast<std::uint32_t>(sequence->total_rounds());
    res.restarts = static_cast<std::uint32_t>(sequence->total_restarts());
    res.stop_reason = last.stop_reason;
    if (!last.trace.empty()) {
      res.relaxation_cost = last.trace.back().cost;
      res.grad_norm = last.trace.back().grad_norm;
    }
    res.certified = sequence->certified();
    if (!sequence->certificates().empty())
      res.min_eigenvalue = sequence->certificates().back().result.min_eigenvalue;
    res.certificate_rounds = static_cast<std::uint32_t>(sequence->certificate_iterations());
    res.escape_rounds = static_cast<std::uint32_t>(sequence->escape_trials());
  }
  res.final_rank = static_cast<std::uint32_t>(state.rank());
  const auto t1 = std::chrono::steady_clock::now();

  Rounding rounding(local, layout, state, mail);
  res = rounding.run(std::move(res));
  if (sequence) {
    double escape_bytes = 0.0;
    res.certificate_bytes = static_cast<std::uint64_t>(
        rounding.sum_over_agents(kTraffic, static_cast<double>(mail.certificate_bytes),
                                 static_cast<double>(mail.escape_bytes), &escape_bytes));
    res.escape_bytes = static_cast<std::uint64_t>(escape_bytes);
  }
  res.solve_s = std::chrono::duration<double>(t1 - t0).count();
  res.rounding_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  res.wait_s = mail.wait_s;
  res.send_s = mail.send_s;
  res.rounding_steps = mail.gathers;

  if (local.agent_id == 0 && res.certified) {  // before the final report, which ends the wait
    RoundStatusMessage c;
    c.round = res.rounds;
    c.phase = kCertificateReportPhase;
    c.sender = 0;
    c.cost = res.min_eigenvalue;
    c.grad_norm_sq = res.certificate_rounds;
    c.block_grad_norm = res.final_rank;
    c.restart_vote = *res.certified;
    c.done_vote = true;
    channel.send(OutgoingMessage{c, true, {}});
    RoundStatusMessage b;
    b.round = res.rounds;
    b.phase = kCertificateBytesPhase;
    b.sender = 0;
    b.cost = static_cast<double>(res.certificate_bytes);
    b.grad_norm_sq = static_cast<double>(res.escape_bytes);
    b.block_grad_norm = res.escape_rounds;
    channel.send(OutgoingMessage{b, true, {}});
  }
  if (local.agent_id == 0) {  // one report for the coordinator's summary
    RoundStatusMessage st;
    st.round = res.rounds;
    st.phase = kFinalReportPhase;
    st.sender = 0;
    st.cost = res.cost;
    st.grad_norm_sq = res.grad_norm * res.grad_norm;
    st.block_grad_norm = static_cast<double>(res.restarts);
    channel.send(OutgoingMessage{st, true, {}});
  }
  return res;
}

}  // namespace tessera::agent
