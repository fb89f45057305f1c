#pragma once
// The sums and verdicts one agent computes over its view for GNC's exchanges (GncAgent sends
// them, GncLocalTerms supplies the per-measurement terms): the start vote's TLS costs at two
// starts, the kept set's costs at the iterate and a candidate start, the largest residual that
// may be rejected (mu's start), the weight spread (the stop vote) and the inlier passes'
// re-check verdict with its effect on the rejected set.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "robust/gnc_local_terms.hpp"

namespace tessera {

/// Sum of the TLS terms of the measurements this agent weighs at two starts (own block,
/// neighbours' public poses each): (at the first, at the second).
std::pair<double, double> start_vote_costs(const GncLocalTerms& terms, const Eigen::MatrixXd& Y,
                                           const Eigen::MatrixXd& neighbours,
                                           const Eigen::MatrixXd& Y_other,
                                           const Eigen::MatrixXd& other_neighbours);

/// Sum of the squared residuals of the measurements this agent weighs that are not in
/// `rejected` (file positions, ascending), at two starts: (at the first, at the second).
std::pair<double, double> kept_set_costs(const GncLocalTerms& terms,
                                         const std::vector<std::uint64_t>& index,
                                         const std::vector<std::uint64_t>& rejected,
                                         const Eigen::MatrixXd& Y,
                                         const Eigen::MatrixXd& neighbours,
                                         const Eigen::MatrixXd& Y_other,
                                         const Eigen::MatrixXd& other_neighbours);

/// The largest squared residual over the measurements this agent weighs that may be rejected
/// and are not `dropped` (per measurement of the agent): mu's start is taken from the max.
double largest_rejectable_residual(const GncLocalTerms& terms, const std::vector<bool>& dropped,
                                   const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours);

/// The measurements this agent weighs that TLS's weights reject (w < 1/2), as file indices.
std::vector<std::uint64_t> rejected_by_weight(const GncLocalTerms& terms,
                                              const std::vector<std::uint64_t>& index,
                                              const std::vector<double>& weights);

/// The cut measurements (ends owned by different agents) this agent weighs at weight 0, as file
/// indices: they leave the next solve's block layout.
std::vector<std::uint64_t> zero_weight_cut(const GncLocalTerms& terms,
                                           const std::vector<Measurement>& measurements,
                                           const std::vector<int>& owner,
                                           const std::vector<std::uint64_t>& index,
                                           const std::vector<double>& weights);

/// sum w (1 - w) over the measurements this agent weighs: the stop vote.
double weight_spread(const GncLocalTerms& terms, const std::vector<double>& weights);

/// RobustOptions::jump_band: how many of the measurements this agent weighs (that may be
/// rejected and were not set aside) have r^2 in (c^2 / band, band c^2) at the iterate Y, or with
/// `inside` false in (c^2, band c^2) (RobustOptions::jump_band_inside). The caller picks the band
/// (RobustOptions::jump_band, widened at small mu up to jump_band_max).
int near_bound_count(const GncLocalTerms& terms, const std::vector<bool>& dropped,
                     const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours, double band,
                     bool inside);

/// TLS's verdict as a weight, from a GNC weight w at mu: 1 when w >= tls_weight(c^2, c^2, mu)
/// (r^2 <= c^2: w falls as r grows), else 0. A function of the weight alone, so the owner and
/// the other end of a cut measurement, which holds only the weight it was sent, agree.
double tls_verdict_weight(double w, double mu);

/// TLS's own verdict at the kept set's solution over the measurements this agent weighs.
struct RecheckVerdict {
  std::vector<std::uint64_t> taken_back;  ///< Rejected, within the bound: back in (weight 1).
  std::vector<std::uint64_t> cut_now;     ///< Kept, beyond the bound: out (weight 0).
  /// Kept, within the bound, but above probe_ratio x the median residual of the kept
  /// measurements the agent weighs (RobustOptions::recheck_probes), when their mean is above
  /// probe_tail_ratio x that median: what a probe cuts. Also rejected ones beyond the bound but
  /// within GncLocalTerms::return_bound(): what a probe brings back. Not a change of the
  /// verdict (empty() ignores it).
  std::vector<std::uint64_t> probe;
  bool empty() const { return taken_back.empty() && cut_now.empty(); }
};
/// `probe_ratio` 0: no probe list.
RecheckVerdict recheck_verdict(const GncLocalTerms& terms, const std::vector<std::uint64_t>& index,
                               const std::vector<std::uint64_t>& rejected, const Eigen::MatrixXd& Y,
                               const Eigen::MatrixXd& neighbours, double probe_ratio = 0,
                               double probe_tail_ratio = 0);

/// The TLS cost of the measurements this agent weighs (known inliers r^2, the others
/// min(r^2, c^2)): what a probe must lower to stay.
double tls_cost(const GncLocalTerms& terms, const Eigen::MatrixXd& Y,
                const Eigen::MatrixXd& neighbours);

/// How many measurements one re-check moved.
struct RecheckCounts {
  std::size_t readmitted = 0;
  std::size_t late_rejected = 0;
};
/// Applies every agent's verdict (gathered in `verdict`; sorted here) to `weights` (per
/// measurement of `index`) and to `rejected` (ascending, stays so). A probe's list is applied
/// as `cut_now`: the ids in it that are already rejected come back instead (a probe flips its
/// measurements).
RecheckCounts apply_recheck(RecheckVerdict& verdict, const std::vector<std::uint64_t>& index,
                            std::vector<std::uint64_t>& rejected, std::vector<double>& weights);

}  // namespace tessera
