#include "robust/gnc_messages.hpp"

#include <algorithm>
#include <stdexcept>

#include "distributed/measurement_block.hpp"
#include "distributed/pose_block_codec.hpp"

namespace tessera {

namespace {

std::string agent_prefix(int id) {
  return "agent " + std::to_string(id) + ": ";
}

bool wanted(const std::vector<std::uint64_t>* rejected, std::uint64_t id) {
  return !rejected || !std::binary_search(rejected->begin(), rejected->end(), id);
}

}  // namespace

std::vector<std::uint32_t> other_agents(std::uint32_t me, int num_agents) {
  std::vector<std::uint32_t> others;
  for (std::uint32_t a = 0; a < static_cast<std::uint32_t>(num_agents); ++a)
    if (a != me) others.push_back(a);
  return others;
}

void broadcast_status(RoundStatusMessage st, std::uint32_t me, std::uint32_t phase, int num_agents,
                      std::vector<OutgoingMessage>& out) {
  if (num_agents <= 1) return;
  st.phase = phase;
  st.sender = me;
  out.push_back(OutgoingMessage{std::move(st), true, {}});
}

const PoseBlockMessage& expect_pose_block(const ProtocolMessage& m, int me,
                                          const std::string& what) {
  const auto* block = std::get_if<PoseBlockMessage>(&m);
  if (!block) throw std::runtime_error("agent " + std::to_string(me) + ": " + what);
  return *block;
}

const RoundStatusMessage& expect_status(const ProtocolMessage& m, int me, const std::string& what) {
  const auto* st = std::get_if<RoundStatusMessage>(&m);
  if (!st) throw std::runtime_error("agent " + std::to_string(me) + ": " + what);
  return *st;
}

RoundStatusMessage vote_message(const std::pair<double, double>& sums) {
  RoundStatusMessage st;
  st.cost = sums.first;
  st.grad_norm_sq = sums.second;
  return st;
}

RoundStatusMessage weights_message(std::uint32_t to, double spread, int crossed, int near_bound,
                                   const GncAgentInput& in, const GncLocalTerms& terms,
                                   const std::vector<double>& weights, bool low_too,
                                   double kept_cost) {
  RoundStatusMessage st;
  st.grad_norm_sq = spread;
  st.cost = crossed;
  st.block_grad_norm = kept_cost;
  st.near_bound = static_cast<std::uint32_t>(near_bound);
  for (std::size_t k : terms.owned()) {
    const Measurement& m = in.measurements[k];
    const auto other = static_cast<std::uint32_t>(in.owner[std::max(m.i, m.j)]);
    const bool cut = in.owner[m.i] != in.owner[m.j];
    if (other == to || (terms.known_connected() && cut && weights[k] == 0) ||
        (low_too && terms.may_reject(k) && weights[k] < 0.5)) {
      st.measurement_ids.push_back(in.measurement_index[k]);
      st.weights.push_back(weights[k]);
    }
  }
  return st;
}

void read_weights_message(const RoundStatusMessage& st, std::uint32_t sender,
                          const GncAgentInput& in, std::vector<double>& weights,
                          std::vector<std::uint64_t>& zero_cut,
                          std::vector<std::pair<std::uint64_t, double>>& low) {
  const std::string me = agent_prefix(in.id);
  if (st.weights.size() != st.measurement_ids.size())
    throw std::runtime_error(me + "weights from agent " + std::to_string(sender) +
                             " do not match their measurements");
  for (std::size_t q = 0; q < st.weights.size(); ++q) {
    const std::uint64_t id = st.measurement_ids[q];
    if (id >= in.structure.size() ||
        in.owner[std::min(in.structure[id].first, in.structure[id].second)] !=
            static_cast<int>(sender))
      throw std::runtime_error(me + "agent " + std::to_string(sender) +
                               " sent the weight of measurement " + std::to_string(id) +
                               ", not its own");
    if (const auto k = position_of(in.measurement_index, id)) weights[*k] = st.weights[q];
    const auto [i, j] = in.structure[id];
    if (st.weights[q] == 0 && in.owner[i] != in.owner[j]) zero_cut.push_back(id);
    if (st.weights[q] < 0.5) low.emplace_back(id, st.weights[q]);
  }
}

PoseBlockMessage owned_values_block(const GncAgentInput& in, const GncLocalTerms& terms,
                                    const std::vector<std::uint64_t>* rejected,
                                    std::uint32_t phase) {
  std::vector<const Measurement*> values;
  std::vector<std::uint64_t> index;
  for (std::size_t k : terms.owned())
    if (wanted(rejected, in.measurement_index[k])) {
      values.push_back(&in.measurements[k]);
      index.push_back(in.measurement_index[k]);
    }
  return encode_measurement_block(static_cast<std::uint32_t>(in.id), phase, in.d, values, index);
}

void append_owned_values(const GncAgentInput& in, const GncLocalTerms& terms,
                         const std::vector<std::uint64_t>* rejected, GatheredValues& values) {
  for (std::size_t k : terms.owned())
    if (wanted(rejected, in.measurement_index[k]))
      values.emplace_back(in.measurement_index[k], in.measurements[k]);
}

RoundStatusMessage readmitted_message(const RecheckVerdict& verdict, double tls_cost) {
  RoundStatusMessage st;
  st.measurement_ids = verdict.taken_back;
  st.weights.assign(verdict.taken_back.size(), 1.0);
  st.measurement_ids.insert(st.measurement_ids.end(), verdict.cut_now.begin(),
                            verdict.cut_now.end());
  st.weights.resize(st.measurement_ids.size(), 0.0);
  st.measurement_ids.insert(st.measurement_ids.end(), verdict.probe.begin(), verdict.probe.end());
  st.weights.resize(st.measurement_ids.size(), 0.5);
  st.cost = tls_cost;
  return st;
}

void read_readmitted_message(const RoundStatusMessage& st, std::uint32_t sender, int receiver,
                             RecheckVerdict& into) {
  // Weight 1: taken back; 0: rejected at the kept set's solution (no weights: taken back).
  if (!st.weights.empty() && st.weights.size() != st.measurement_ids.size())
    throw std::runtime_error(agent_prefix(receiver) + "re-check from agent " +
                             std::to_string(sender) + " does not match its measurements");
  for (std::size_t q = 0; q < st.measurement_ids.size(); ++q) {
    const double w = st.weights.empty() ? 1.0 : st.weights[q];
    (w > 0.75   ? into.taken_back
     : w < 0.25 ? into.cut_now
                : into.probe)
        .push_back(st.measurement_ids[q]);
  }
}

PoseBlockMessage kept_start_block(const Eigen::MatrixXd& Y, const std::vector<std::size_t>& ids,
                                  int d, std::uint32_t phase, const Eigen::MatrixXd& nb,
                                  const std::vector<std::size_t>& nb_ids) {
  PoseBlockMessage b;
  b.sender = 0;
  b.phase = phase;
  b.kind = BlockKind::kP;
  b.rank = static_cast<std::uint32_t>(Y.rows());
  b.dim = static_cast<std::uint32_t>(d);
  for (std::size_t id : ids) b.pose_ids.push_back(static_cast<std::uint32_t>(id));
  for (std::size_t id : nb_ids) b.pose_ids.push_back(static_cast<std::uint32_t>(id));
  b.data.assign(Y.data(), Y.data() + Y.size());
  b.data.insert(b.data.end(), nb.data(), nb.data() + nb.size());
  return b;
}

Eigen::MatrixXd read_kept_start(const PoseBlockMessage& block, const std::vector<std::size_t>& own,
                                Eigen::Index r, int d, int receiver,
                                const std::vector<std::size_t>& nb, Eigen::MatrixXd& nb_out) {
  const Eigen::Index w = (d + 1) * r;
  if (block.rank != static_cast<std::uint32_t>(r) || block.pose_ids.size() < own.size() ||
      block.data.size() != block.pose_ids.size() * static_cast<std::size_t>(w) ||
      !std::equal(own.begin(), own.end(), block.pose_ids.begin()))
    throw std::runtime_error(agent_prefix(receiver) +
                             "malformed start of the kept set from agent 0");
  // The own poses, then the neighbours' (decoded as two blocks of the same sender).
  PoseBlockMessage part = block;
  part.pose_ids.resize(own.size());
  part.data.resize(own.size() * static_cast<std::size_t>(w));
  Eigen::MatrixXd Y(r, (d + 1) * static_cast<Eigen::Index>(own.size()));
  decode_neighbour_poses(part, own, d, receiver, Y);
  if (block.pose_ids.size() > own.size()) {
    part.pose_ids.assign(block.pose_ids.begin() + static_cast<std::ptrdiff_t>(own.size()),
                         block.pose_ids.end());
    part.data.assign(block.data.begin() + static_cast<std::ptrdiff_t>(own.size()) * w,
                     block.data.end());
    nb_out = Eigen::MatrixXd::Zero(r, (d + 1) * static_cast<Eigen::Index>(nb.size()));
    decode_neighbour_poses(part, nb, d, receiver, nb_out);
  }
  return Y;
}

}  // namespace tessera
