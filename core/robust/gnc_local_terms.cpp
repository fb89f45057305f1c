#include "robust/gnc_local_terms.hpp"

#include <algorithm>
#include <tessera/graph/connectivity.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/tls_weights.hpp>

namespace tessera {

namespace {

// Endpoints only: what connectivity and the known-inlier rule need.
Measurement endpoints(const std::pair<std::uint32_t, std::uint32_t>& e) {
  Measurement m;
  m.i = e.first;
  m.j = e.second;
  return m;
}

}  // namespace

std::size_t components_without(
    std::size_t num_poses, int d,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& dropped, bool only_known, const std::vector<bool>& known) {
  PoseGraph g;
  g.d = d;
  g.num_poses = num_poses;
  for (std::size_t e = 0; e < structure.size(); ++e) {
    if (only_known && !known[e]) continue;
    if (std::binary_search(dropped.begin(), dropped.end(), static_cast<std::uint64_t>(e))) continue;
    g.measurements.push_back(endpoints(structure[e]));
  }
  return count_components(g);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> structure_without(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& dropped) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  out.reserve(structure.size());
  for (std::size_t e = 0; e < structure.size(); ++e)
    if (!std::binary_search(dropped.begin(), dropped.end(), static_cast<std::uint64_t>(e)))
      out.push_back(structure[e]);
  return out;
}

std::optional<std::size_t> position_of(const std::vector<std::uint64_t>& index, std::uint64_t id) {
  const auto pos = std::lower_bound(index.begin(), index.end(), id);
  if (pos == index.end() || *pos != id) return std::nullopt;
  return static_cast<std::size_t>(pos - index.begin());
}

GncLocalTerms::GncLocalTerms(const GncAgentInput& in, const RobustOptions& robust,
                             const BlockLayout& base)
    : in_(in), base_(base) {
  // Every agent knows every measurement's known-inlier status (rule + flags), hence how many may
  // be rejected (c^2's default) and whether the known inliers alone connect the poses.
  known_.resize(in_.structure.size());
  std::size_t candidates = 0;
  for (std::size_t e = 0; e < in_.structure.size(); ++e) {
    known_[e] = is_known_inlier(endpoints(in_.structure[e]), robust.known_inliers) ||
                (!in_.known_inlier.empty() && in_.known_inlier[e]);
    candidates += known_[e] ? 0 : 1;
  }
  c2_ = tls_threshold_squared(robust, in_.d, candidates);
  return_c2_ = robust.probe_return_ratio * c2_;
  known_connected_ = components_without(in_.num_poses, in_.d, in_.structure, {}, true, known_) <= 1;
  for (std::size_t k = 0; k < in_.measurements.size(); ++k) {
    const Measurement& x = in_.measurements[k];
    if (weight_owner(x, in_.owner) == in_.id) owned_.push_back(k);
    for (std::size_t p : {x.i, x.j})
      if (in_.owner[p] != in_.id) neighbours_.push_back(p);
  }
  std::sort(neighbours_.begin(), neighbours_.end());
  neighbours_.erase(std::unique(neighbours_.begin(), neighbours_.end()), neighbours_.end());
}

bool GncLocalTerms::may_reject(std::size_t k) const {
  return !known_[in_.measurement_index[k]];
}

double GncLocalTerms::tls_term(std::size_t k, double r2) const {
  return may_reject(k) ? std::min(r2, c2_) : r2;
}

double GncLocalTerms::residual_squared(std::size_t k, const Eigen::MatrixXd& own_block,
                                       const Eigen::MatrixXd& neighbour_block) const {
  const Measurement& m = in_.measurements[k];
  const Eigen::Index w = in_.d + 1;
  const auto& own = base_.poses[static_cast<std::size_t>(in_.id)];
  auto block = [&](std::size_t p) -> Eigen::MatrixXd {
    if (in_.owner[p] == in_.id) {
      const auto s = std::lower_bound(own.begin(), own.end(), p) - own.begin();
      return own_block.middleCols(w * s, w);
    }
    const auto s =
        std::lower_bound(neighbours_.begin(), neighbours_.end(), p) - neighbours_.begin();
    return neighbour_block.middleCols(w * s, w);
  };
  return lifted_residual_squared(m, block(m.i), block(m.j));
}

}  // namespace tessera
