#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/distributed/coarse_exchange.hpp>

namespace tessera {

namespace {

[[noreturn]] void malformed(std::uint32_t sender, const std::string& why) {
  throw std::runtime_error("malformed message: coarse exchange from agent " +
                           std::to_string(sender) + ": " + why);
}

}  // namespace

std::vector<int> coarse_unknowns_of(const CoarseSpace* space, const BlockLayout& layout,
                                    int agent) {
  const auto a = static_cast<std::size_t>(agent);
  std::vector<int> out;
  if (!space) {
    out.push_back(agent);
    out.insert(out.end(), layout.adjacent[a].begin(), layout.adjacent[a].end());
  } else {
    auto add = [&](std::size_t i) {
      for (std::size_t e = space->weight_start[i]; e < space->weight_start[i + 1]; ++e)
        out.push_back(space->weight_aggregate[e]);
    };
    for (std::size_t i : layout.poses[a]) add(i);
    // The copies of neighbour b's poses this agent holds: what b publishes to it.
    for (int b : layout.adjacent[a]) {
      const int k = layout.adjacency_index(b, agent);
      for (std::size_t i :
           layout.public_to[static_cast<std::size_t>(b)][static_cast<std::size_t>(k)])
        add(i);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

PoseBlockMessage coarse_terms_message(int sender, std::uint32_t round, std::uint32_t phase,
                                      std::vector<double> terms) {
  PoseBlockMessage m;
  m.round = round;
  m.sender = static_cast<std::uint32_t>(sender);
  m.phase = phase;
  m.kind = BlockKind::kY;
  m.rank = static_cast<std::uint32_t>(terms.size());
  m.dim = 0;
  m.pose_ids = {0};
  m.data = std::move(terms);
  return m;
}

const std::vector<double>& coarse_terms_of(const ProtocolMessage& message) {
  const auto* p = std::get_if<PoseBlockMessage>(&message);
  if (!p) malformed(std::get<RoundStatusMessage>(message).sender, "a status instead of terms");
  if (p->pose_ids.size() != 1 || p->dim != 0 || p->data.size() != p->rank)
    malformed(p->sender, "terms not shaped as one column of values");
  return p->data;
}

PoseBlockMessage coarse_motions_message(int sender, std::uint32_t round, std::uint32_t phase,
                                        const std::vector<int>& unknowns,
                                        const std::vector<Eigen::MatrixXd>& motions,
                                        double decrease, bool applied) {
  PoseBlockMessage m;
  m.round = round;
  m.sender = static_cast<std::uint32_t>(sender);
  m.phase = phase;
  m.kind = BlockKind::kY;
  const Eigen::Index r = motions.empty() ? 0 : motions.front().rows();
  m.rank = static_cast<std::uint32_t>(r);
  m.dim = static_cast<std::uint32_t>(r);
  if (!applied) return m;
  const std::size_t width = static_cast<std::size_t>(r * (r + 1));
  m.pose_ids.reserve(unknowns.size());
  m.data.reserve((unknowns.size() + 1) * width);
  for (int u : unknowns) {
    const Eigen::MatrixXd& Z = motions[static_cast<std::size_t>(u)];
    m.pose_ids.push_back(static_cast<std::uint32_t>(u));
    m.data.insert(m.data.end(), Z.data(), Z.data() + Z.size());
  }
  // The decrease as one more "pose" of the same shape, so the message stays a pose block.
  m.pose_ids.push_back(kCoarseDecreaseId);
  m.data.push_back(decrease);
  m.data.resize(m.data.size() + width - 1, 0.0);
  return m;
}

ReceivedCoarseMotions read_coarse_motions(const ProtocolMessage& message, int r, int count,
                                          const std::vector<int>& expected) {
  const auto* p = std::get_if<PoseBlockMessage>(&message);
  if (!p) malformed(std::get<RoundStatusMessage>(message).sender, "a status instead of motions");
  ReceivedCoarseMotions out;
  Eigen::MatrixXd identity = Eigen::MatrixXd::Zero(r, r + 1);
  identity.leftCols(r).setIdentity();
  out.motions.assign(static_cast<std::size_t>(count), identity);
  if (p->pose_ids.empty() && p->data.empty()) return out;  // not applied
  const std::size_t width = static_cast<std::size_t>(r * (r + 1));
  if (p->rank != static_cast<std::uint32_t>(r) || p->dim != static_cast<std::uint32_t>(r))
    malformed(p->sender,
              "motions of rank " + std::to_string(p->rank) + ", expected " + std::to_string(r));
  if (p->pose_ids.size() != expected.size() + 1 || p->pose_ids.back() != kCoarseDecreaseId ||
      !std::equal(expected.begin(), expected.end(), p->pose_ids.begin(),
                  [](int a, std::uint32_t b) { return static_cast<std::uint32_t>(a) == b; }))
    malformed(p->sender, "motions of other coarse unknowns than this agent's");
  if (p->data.size() != (expected.size() + 1) * width)
    malformed(p->sender, std::to_string(p->data.size()) + " values, expected " +
                             std::to_string((expected.size() + 1) * width));
  for (std::size_t k = 0; k < expected.size(); ++k)
    out.motions[static_cast<std::size_t>(expected[k])] =
        Eigen::Map<const Eigen::MatrixXd>(p->data.data() + k * width, r, r + 1);
  out.applied = true;
  out.decrease = p->data[expected.size() * width];
  return out;
}

}  // namespace tessera
