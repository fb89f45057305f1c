#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <tessera/solvers/preconditioner_edges.hpp>
#include <tessera/util/input_error.hpp>

#include "solvers/cholmod_checked.hpp"

namespace tessera {

void PreconditionerEdgeOptions::validate() const {
  if (!(max_flops >= 0)) throw InputError("PreconditionerEdgeOptions.max_flops must be >= 0");
}

namespace {

// Predicted flops of the factor of the pose adjacency of measurements[order[0..count)] (AMD,
// like the preconditioner's own analysis), scaled to (d+1) x (d+1) blocks. The scalar analysis
// is (d+1)^2 times smaller than the data matrix's, so the selection's bisection costs little
// beside one factorization.
double prefix_flops(int d, std::size_t num_poses, const std::vector<Measurement>& measurements,
                    const std::vector<std::size_t>& order, std::size_t count) {
  using Sparse = Eigen::SparseMatrix<double>;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(num_poses + 2 * count);
  for (std::size_t p = 0; p < num_poses; ++p) {
    const auto k = static_cast<Eigen::Index>(p);
    entries.emplace_back(k, k, 1.0);
  }
  for (std::size_t n = 0; n < count; ++n) {
    const Measurement& m = measurements[order[n]];
    const auto i = static_cast<Eigen::Index>(m.i), j = static_cast<Eigen::Index>(m.j);
    entries.emplace_back(std::max(i, j), std::min(i, j), 1.0);
  }
  const auto n = static_cast<Eigen::Index>(num_poses);
  Sparse A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  Eigen::CholmodSimplicialLLT<Sparse> llt;
  cholmod_common& c = llt.cholmod();
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  llt.analyzePattern(A);
  if (llt.info() != Eigen::Success || cholmod_analysis_failed(llt))
    throw_cholmod_failure("select_preconditioner_edges", "analysis", llt.cholmod().status, A.rows(),
                          A.cols());
  const double block = d + 1.0;
  return block * block * block * llt.cholmod().fl;
}

}  // namespace

double predicted_factor_flops(int d, std::size_t num_poses,
                              const std::vector<Measurement>& measurements) {
  std::vector<std::size_t> all(measurements.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  return prefix_flops(d, num_poses, measurements, all, all.size());
}

PreconditionerEdges select_preconditioner_edges(int d, std::size_t num_poses,
                                                const std::vector<Measurement>& measurements,
                                                const std::vector<double>& weights,
                                                const std::vector<bool>& required,
                                                const PreconditionerEdgeOptions& options) {
  options.validate();
  const std::size_t m = measurements.size();
  if (weights.size() != m || (!required.empty() && required.size() != m))
    throw std::invalid_argument("select_preconditioner_edges: one weight (flag) per measurement");
  PreconditionerEdges out;
  out.kept.resize(m);
  std::iota(out.kept.begin(), out.kept.end(), std::size_t{0});
  if (options.max_flops == 0) return out;
  out.full_flops = prefix_flops(d, num_poses, measurements, out.kept, m);
  out.kept_flops = out.full_flops;
  out.analyses = 1;
  if (out.full_flops <= options.max_flops) return out;

  // Required first, then by weight (high first), then by pose-id distance (short first).
  const auto span = [&](std::size_t e) {
    const Measurement& x = measurements[e];
    return x.i > x.j ? x.i - x.j : x.j - x.i;
  };
  std::vector<std::size_t> order = out.kept;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const bool ra = !required.empty() && required[a], rb = !required.empty() && required[b];
    if (ra != rb) return ra;
    if (weights[a] != weights[b]) return weights[a] > weights[b];
    return span(a) < span(b);
  });
  const std::size_t must =
      required.empty()
          ? 0
          : static_cast<std::size_t>(std::count(required.begin(), required.end(), true));
  // Adding edges can only add fill under a fixed ordering; AMD reorders, so the flops are only
  // nearly monotone in the prefix length, which is all a bisection for the budget needs.
  std::size_t lo = must, hi = m;  // flops(lo) is taken as fitting, flops(hi) does not fit
  double lo_flops = -1;
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    const double f = prefix_flops(d, num_poses, measurements, order, mid);
    ++out.analyses;
    if (f <= options.max_flops) {
      lo = mid;
      lo_flops = f;
    } else {
      hi = mid;
    }
  }
  if (lo_flops < 0) {
    lo_flops = prefix_flops(d, num_poses, measurements, order, lo);
    ++out.analyses;
  }
  out.all = false;
  out.kept.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(lo));
  std::sort(out.kept.begin(), out.kept.end());
  out.kept_flops = lo_flops;
  return out;
}

}  // namespace tessera
