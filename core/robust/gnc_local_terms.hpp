#pragma once
// The math of GNC-TLS over one agent's view, apart from the state machine (GncAgent) and its
// messages: which measurements this agent weighs (the owner of the lower pose id), which may be
// rejected (known inliers never are), the bound c^2 and each measurement's squared residual at a
// lifted iterate from its own block and its neighbours' public poses.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

namespace tessera {

class GncLocalTerms {
 public:
  /// `in` and `base` (the layout of every measurement) must outlive this object.
  GncLocalTerms(const GncAgentInput& in, const RobustOptions& robust, const BlockLayout& base);

  /// Indices into in.measurements of the measurements this agent weighs.
  const std::vector<std::size_t>& owned() const { return owned_; }
  /// Other ends of the own measurements, ascending: the columns of a neighbour block.
  const std::vector<std::size_t>& neighbours() const { return neighbours_; }
  /// Per measurement of the whole graph (file order): never down-weighted.
  const std::vector<bool>& known() const { return known_; }
  /// The known inliers alone connect the poses.
  bool known_connected() const { return known_connected_; }
  double c2() const { return c2_; }
  /// RobustOptions::probe_return_ratio x c^2: how far beyond the bound a rejected measurement
  /// may lie and still be brought back by a probe.
  double return_bound() const { return return_c2_; }

  bool may_reject(std::size_t k) const;
  /// The measurement's term of the TLS cost: r^2 for a known inlier, min(r^2, c^2) otherwise.
  double tls_term(std::size_t k, double r2) const;
  /// The measurement's term of the relaxed objective at the lifted iterate given by the own
  /// block's columns and the neighbours' public poses (columns in neighbours() order).
  double residual_squared(std::size_t k, const Eigen::MatrixXd& own_block,
                          const Eigen::MatrixXd& neighbour_block) const;

 private:
  const GncAgentInput& in_;
  const BlockLayout& base_;
  std::vector<std::size_t> owned_, neighbours_;
  std::vector<bool> known_;
  bool known_connected_ = false;
  double c2_ = 0.0;
  double return_c2_ = 0.0;
};

/// How many parts the measurements of `structure` not in `dropped` (ascending) split the poses
/// into; with `only_known`, only the measurements flagged in `known`.
std::size_t components_without(
    std::size_t num_poses, int d,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& dropped, bool only_known, const std::vector<bool>& known);

/// `structure` without the measurements in `dropped` (ascending).
std::vector<std::pair<std::uint32_t, std::uint32_t>> structure_without(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& dropped);

/// Where the measurement of file position `id` is in `index` (ascending), if it is there.
std::optional<std::size_t> position_of(const std::vector<std::uint64_t>& index, std::uint64_t id);

}  // namespace tessera
