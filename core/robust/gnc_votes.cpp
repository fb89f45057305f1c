#include "robust/gnc_votes.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace tessera {

namespace {

bool contains(const std::vector<std::uint64_t>& sorted, std::uint64_t id) {
  return std::binary_search(sorted.begin(), sorted.end(), id);
}

}  // namespace

std::pair<double, double> start_vote_costs(const GncLocalTerms& terms, const Eigen::MatrixXd& Y,
                                           const Eigen::MatrixXd& neighbours,
                                           const Eigen::MatrixXd& Y_other,
                                           const Eigen::MatrixXd& other_neighbours) {
  double at_first = 0, at_second = 0;
  for (std::size_t k : terms.owned()) {
    at_first += terms.tls_term(k, terms.residual_squared(k, Y, neighbours));
    at_second += terms.tls_term(k, terms.residual_squared(k, Y_other, other_neighbours));
  }
  return {at_first, at_second};
}

std::pair<double, double> kept_set_costs(const GncLocalTerms& terms,
                                         const std::vector<std::uint64_t>& index,
                                         const std::vector<std::uint64_t>& rejected,
                                         const Eigen::MatrixXd& Y,
                                         const Eigen::MatrixXd& neighbours,
                                         const Eigen::MatrixXd& Y_other,
                                         const Eigen::MatrixXd& other_neighbours) {
  double at_first = 0, at_second = 0;
  for (std::size_t k : terms.owned())
    if (!contains(rejected, index[k])) {
      at_first += terms.residual_squared(k, Y, neighbours);
      at_second += terms.residual_squared(k, Y_other, other_neighbours);
    }
  return {at_first, at_second};
}

double largest_rejectable_residual(const GncLocalTerms& terms, const std::vector<bool>& dropped,
                                   const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours) {
  double max_r2 = 0;
  for (std::size_t k : terms.owned())
    if (terms.may_reject(k) && !dropped[k])
      max_r2 = std::max(max_r2, terms.residual_squared(k, Y, neighbours));
  return max_r2;
}

std::vector<std::uint64_t> rejected_by_weight(const GncLocalTerms& terms,
                                              const std::vector<std::uint64_t>& index,
                                              const std::vector<double>& weights) {
  std::vector<std::uint64_t> out;
  for (std::size_t k : terms.owned())
    if (weights[k] < 0.5) out.push_back(index[k]);
  return out;
}

std::vector<std::uint64_t> zero_weight_cut(const GncLocalTerms& terms,
                                           const std::vector<Measurement>& measurements,
                                           const std::vector<int>& owner,
                                           const std::vector<std::uint64_t>& index,
                                           const std::vector<double>& weights) {
  std::vector<std::uint64_t> out;
  for (std::size_t k : terms.owned()) {
    const Measurement& m = measurements[k];
    if (weights[k] == 0 && owner[m.i] != owner[m.j]) out.push_back(index[k]);
  }
  return out;
}

double weight_spread(const GncLocalTerms& terms, const std::vector<double>& weights) {
  double spread = 0;
  for (std::size_t k : terms.owned()) spread += weights[k] * (1 - weights[k]);
  return spread;
}

int near_bound_count(const GncLocalTerms& terms, const std::vector<bool>& dropped,
                     const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours, double band,
                     bool inside) {
  int near = 0;
  const double lo = inside ? terms.c2() / band : terms.c2(), hi = terms.c2() * band;
  for (std::size_t k : terms.owned())
    if (terms.may_reject(k) && !dropped[k]) {
      const double r2 = terms.residual_squared(k, Y, neighbours);
      if (r2 > lo && r2 < hi) ++near;
    }
  return near;
}

double tls_verdict_weight(double w, double mu) {
  // tls_weight(c^2, c^2, mu) = sqrt(mu (mu + 1)) - mu, whatever c.
  return w >= std::sqrt(mu * (mu + 1)) - mu ? 1.0 : 0.0;
}

RecheckVerdict recheck_verdict(const GncLocalTerms& terms, const std::vector<std::uint64_t>& index,
                               const std::vector<std::uint64_t>& rejected, const Eigen::MatrixXd& Y,
                               const Eigen::MatrixXd& neighbours, double probe_ratio,
                               double probe_tail_ratio) {
  // A rejected measurement within the bound was misjudged on a rough iterate; a kept one beyond
  // it is a wrong closure that GNC's iterate fitted with the help of a distortion. Each pass is
  // a descent step of the TLS cost (binary weights given the poses).
  RecheckVerdict v;
  std::vector<std::pair<double, std::uint64_t>> kept;  // (r^2, id) of the kept ones that fit
  for (std::size_t k : terms.owned()) {
    if (!terms.may_reject(k)) continue;
    const std::uint64_t id = index[k];
    const bool was_rejected = contains(rejected, id);
    const double r2 = terms.residual_squared(k, Y, neighbours);
    const bool fits = r2 <= terms.c2();
    if (was_rejected && fits) v.taken_back.push_back(id);
    if (!was_rejected && !fits) v.cut_now.push_back(id);
    if (!was_rejected && fits) kept.emplace_back(r2, id);
    if (probe_ratio > 0 && was_rejected && !fits && r2 <= terms.return_bound())
      v.probe.push_back(id);
  }
  if (probe_ratio > 0 && !kept.empty()) {
    // The median of the agent's own kept residuals: a local scale, so no extra exchange.
    std::vector<double> r2s;
    for (const auto& e : kept) r2s.push_back(e.first);
    auto mid = r2s.begin() + static_cast<std::ptrdiff_t>(r2s.size() / 2);
    std::nth_element(r2s.begin(), mid, r2s.end());
    double sum = 0;
    for (double r2 : r2s) sum += r2;
    // Without a heavy tail (mean near the median, as for residuals that match their
    // information) there is no bend for a probe to undo.
    const bool tail = sum > probe_tail_ratio * *mid * static_cast<double>(r2s.size());
    const double bound = probe_ratio * *mid;
    for (const auto& [r2, id] : kept)
      if (tail && r2 > bound) v.probe.push_back(id);
  }
  return v;
}

double tls_cost(const GncLocalTerms& terms, const Eigen::MatrixXd& Y,
                const Eigen::MatrixXd& neighbours) {
  double f = 0;
  for (std::size_t k : terms.owned())
    f += terms.tls_term(k, terms.residual_squared(k, Y, neighbours));
  return f;
}

RecheckCounts apply_recheck(RecheckVerdict& verdict, const std::vector<std::uint64_t>& index,
                            std::vector<std::uint64_t>& rejected, std::vector<double>& weights) {
  // A probe's already rejected measurements come back (its list arrives as cut_now).
  const auto returning = std::stable_partition(
      verdict.cut_now.begin(), verdict.cut_now.end(),
      [&](std::uint64_t id) { return !std::binary_search(rejected.begin(), rejected.end(), id); });
  verdict.taken_back.insert(verdict.taken_back.end(), returning, verdict.cut_now.end());
  verdict.cut_now.erase(returning, verdict.cut_now.end());
  std::sort(verdict.taken_back.begin(), verdict.taken_back.end());
  std::sort(verdict.cut_now.begin(), verdict.cut_now.end());
  for (std::size_t k = 0; k < index.size(); ++k) {
    if (contains(verdict.taken_back, index[k])) weights[k] = 1.0;
    if (contains(verdict.cut_now, index[k])) weights[k] = 0.0;
  }
  std::vector<std::uint64_t> still;
  std::set_difference(rejected.begin(), rejected.end(), verdict.taken_back.begin(),
                      verdict.taken_back.end(), std::back_inserter(still));
  RecheckCounts counts;
  counts.readmitted = rejected.size() - still.size();
  counts.late_rejected = verdict.cut_now.size();
  rejected.clear();
  std::merge(still.begin(), still.end(), verdict.cut_now.begin(), verdict.cut_now.end(),
             std::back_inserter(rejected));
  return counts;
}

}  // namespace tessera
