#pragma once
// One agent's share of a team's interface matrix as it travels in an all-agent sum: a flag
// (0 = the block's factor failed), the lower triangle of the block's Schur complement on its
// interface (column by column, nG (nG + 1) / 2 values), then a count and that many cut
// couplings whose layout the caller knows. The Hessian's interface solves and the exact trial
// translations read the flag and the triangle the same way.

#include <Eigen/Sparse>
#include <algorithm>
#include <cstddef>
#include <vector>

namespace tessera {

/// Appends the share's triangle to `t` at rows and columns `at`.. `at + nG - 1` (lower
/// triangle), raises `top` to its largest diagonal entry and sets `next` to the count's index.
/// False when the block's factor failed (its flag is 0); calls `malformed` (which throws) when
/// `v` is too short to hold the flag, the triangle and the count.
template <class Malformed>
bool read_schur_triangle(const std::vector<double>& v, Eigen::Index at, Eigen::Index nG,
                         std::vector<Eigen::Triplet<double>>& t, double& top, std::size_t& next,
                         Malformed malformed) {
  if (v.empty()) malformed();
  if (v[0] == 0.0) return false;
  std::size_t k = 1;
  const std::size_t tri = static_cast<std::size_t>(nG * (nG + 1) / 2);
  if (v.size() < k + tri + 1) malformed();
  for (Eigen::Index j = 0; j < nG; ++j)
    for (Eigen::Index i = j; i < nG; ++i) {
      if (i == j) top = std::max(top, v[k]);
      t.emplace_back(at + i, at + j, v[k++]);
    }
  next = k;
  return true;
}

}  // namespace tessera
