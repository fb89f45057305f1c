#include "partition/spectral_layouts.hpp"

#include <Spectra/SymEigsSolver.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <tessera/util/input_error.hpp>
#include <tuple>

#include "partition/kway_refinement.hpp"
#include "solvers/cholmod_checked.hpp"

namespace tessera::partition_detail {

void SpectralLayoutOptions::validate() const {
  auto bad = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw InputError("SpectralLayoutOptions." + field + " = " + value + ": " + rule);
  };
  if (eigenvectors < 1 || eigenvectors > 6)
    bad("eigenvectors", std::to_string(eigenvectors), "must be in 1..6");
  if (max_vertices < 2) bad("max_vertices", std::to_string(max_vertices), "must be >= 2");
  if (max_parts < 2 || max_parts > 64)
    bad("max_parts", std::to_string(max_parts), "must be in 2..64");
  if (max_layouts < 1) bad("max_layouts", std::to_string(max_layouts), "must be >= 1");
  if (rotations < 1 || rotations > 8)
    bad("rotations", std::to_string(rotations), "must be in 1..8");
  if (polish < 0 || polish > 8) bad("polish", std::to_string(polish), "must be in 0..8");
  if (rotation_steps < 1 || rotation_steps > 64)
    bad("rotation_steps", std::to_string(rotation_steps), "must be in 1..64");
  if (lanczos_max_iterations < 1)
    bad("lanczos_max_iterations", std::to_string(lanczos_max_iterations), "must be >= 1");
  if (!std::isfinite(lanczos_tolerance) || lanczos_tolerance <= 0.0 || lanczos_tolerance >= 1.0)
    bad("lanczos_tolerance", std::to_string(lanczos_tolerance), "must be in (0, 1)");
}

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
// Supernodal CHOLMOD: on 3D meshes (grid3D) the factor fills in heavily, which its dense
// supernodal kernels handle well (the embedding is still the dearest step there, ~0.2 s).
using Factor = Eigen::CholmodSupernodalLLT<SparseMatrix>;

// y = P (L + delta I)^{-1} P x with P the projection orthogonal to the constant vector: the
// largest eigenvalues of this operator are 1 / (lambda + delta) for the smallest *nonzero*
// Laplacian eigenvalues lambda (shift-invert converges fast there, plain Lanczos on L would
// crawl through the dense low end of a mesh's spectrum).
class ProjectedInverse {
 public:
  using Scalar = double;
  ProjectedInverse(const Factor& f, Eigen::Index n) : factor_(f), n_(n) {}
  Eigen::Index rows() const { return n_; }
  Eigen::Index cols() const { return n_; }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, n_);
    Eigen::Map<Eigen::VectorXd> y(y_out, n_);
    Eigen::VectorXd px = x.array() - x.mean();
    y = factor_.solve(px);
    y.array() -= y.mean();
  }

 private:
  const Factor& factor_;
  Eigen::Index n_;
};

// Columns: eigenvectors of the m smallest nonzero eigenvalues (empty on failure).
Eigen::MatrixXd embedding(const WorkGraph& g, int m, const SpectralLayoutOptions& opt,
                          Eigen::VectorXd* lambdas) {
  const int n = g.n;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(g.adj.size() + static_cast<std::size_t>(n));
  double total_degree = 0.0;
  for (int v = 0; v < n; ++v) {
    double d = 0.0;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      t.emplace_back(v, g.adj[e], -static_cast<double>(g.ew[e]));
      d += g.ew[e];
    }
    t.emplace_back(v, v, d);
    total_degree += d;
  }
  // A small shift makes L + delta I positive definite; it only moves the spectrum.
  const double delta = 1e-4 * std::max(1.0, total_degree / n);
  for (int v = 0; v < n; ++v) t.emplace_back(v, v, delta);
  SparseMatrix L(n, n);
  L.setFromTriplets(t.begin(), t.end());
  Factor factor;
  factor.cholmod().print = 0;
  // No factor (a resource limit: out of memory, above CHOLMOD's 2^31 entries): no spectral
  // layout, as when the factorization or Lanczos fails; the partitioner's other starts remain.
  factor.analyzePattern(L);
  if (cholmod_analysis_failed(factor)) return {};
  factor.factorize(L);
  if (factor.cholmod().status < CHOLMOD_OK || factor.info() != Eigen::Success) return {};
  ProjectedInverse op(factor, n);
  const Eigen::Index ncv = std::min<Eigen::Index>(n - 1, std::max(2 * m + 1, 20));
  Spectra::SymEigsSolver<ProjectedInverse> eigs(op, m, ncv);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestAlge, opt.lanczos_max_iterations, opt.lanczos_tolerance);
  if (eigs.info() != Spectra::CompInfo::Successful) return {};
  Eigen::VectorXd mu = eigs.eigenvalues();
  *lambdas = (1.0 / mu.array()) - delta;
  Eigen::MatrixXd u = eigs.eigenvectors();
  // Eigenvectors are defined up to sign: fix it (largest-magnitude entry positive) so the
  // layouts do not depend on the solver's arbitrary choice.
  for (int j = 0; j < u.cols(); ++j) {
    Eigen::Index arg = 0;
    u.col(j).cwiseAbs().maxCoeff(&arg);
    if (u(arg, j) < 0) u.col(j) = -u.col(j);
  }
  return u;
}

// Deals the vertices of `order` (in that order) out to blocks first, first+1, ..,
// first+count-1, each getting an equal share of their total weight.
void deal(const WorkGraph& g, const std::vector<int>& order, int first, int count,
          std::vector<int>& part) {
  long long total = 0;
  for (int v : order) total += g.vw[v];
  long long acc = 0;
  int b = 0;
  for (int v : order) {
    // Block b ends once the running weight reaches (b + 1) / count of the total.
    while (b < count - 1 && acc * count >= total * (b + 1)) ++b;
    part[v] = first + b;
    acc += g.vw[v];
  }
}

// Deals a cyclic order (vertices sorted by angle) out to blocks first..first+count-1 as count
// arcs of equal size (vertex counts), choosing among all ns rotations of the arcs the one that
// cuts the fewest edges inside the set (edges to vertices outside it are cut by every rotation
// alike). On a ring the arcs' borders should meet its seams (e.g. where a spiral trajectory
// steps to the next turn), which no fixed angle knows; one shift moves `count` vertices, so the
// sweep costs O(count x edges of the set).
void deal_cyclic(const WorkGraph& g, const std::vector<int>& order, int first, int count,
                 std::vector<int>& part, std::vector<int>& mark, int stamp) {
  const int ns = static_cast<int>(order.size());
  for (int v : order) mark[v] = stamp;
  auto block_at = [&](long long d) { return first + static_cast<int>(d * count / ns); };
  for (int p = 0; p < ns; ++p) part[order[p]] = block_at(p);
  long long cut = 0;
  for (int v : order)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (u < v && mark[u] == stamp && part[u] != part[v]) cut += g.ew[e];
    }
  auto move = [&](int v, int to) {
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (mark[u] != stamp) continue;
      cut += static_cast<long long>(g.ew[e]) *
             (static_cast<int>(part[u] != to) - static_cast<int>(part[u] != part[v]));
    }
    part[v] = to;
  };
  long long best = cut;
  int best_s = 0;
  for (int s = 1; s < ns && count > 1; ++s) {
    // Rotation s - 1 -> s: the vertex at offset 0 wraps to the last block, and the first
    // vertex of every other block joins the block before it.
    move(order[s - 1], first + count - 1);
    for (int j = 1; j < count; ++j) {
      const int d = static_cast<int>((static_cast<long long>(j) * ns + count - 1) / count);
      if (d >= ns) continue;
      move(order[(s - 1 + d) % ns], first + j - 1);
    }
    if (cut < best) {
      best = cut;
      best_s = s;
    }
  }
  for (int p = 0; p < ns; ++p) part[order[(p + best_s) % ns]] = block_at(p);
}

// Splits `vertices` into count arcs of equal *angle* (2 pi / count each) around the origin,
// blocks first..first+count-1, at the rotations that cut the fewest edges inside the set among
// those keeping every block within max_block. Returns up to `rotations` of them (each a block
// per entry of `vertices`), best first, no two within a tenth of an arc of each other; empty if
// no rotation is within the bound. Arcs of equal angle have straight borders on a uniform ring
// (equal counts give staircases there, whose steps cut the edges across them); the runners-up
// matter because a single odd vertex (e.g. at a trajectory's start) can make the rotation that
// meets a ring's seam look one edge worse before refinement fixes that vertex. As the rotation
// t grows from 0 to one arc, each vertex moves once, into the previous arc, when t passes
// (angle mod arc): a sweep over these events visits every distinct rotation.
// `by_phase` lists all vertices of the graph sorted by (angle mod arc width) for this count
// (shared by all sets cut into `count` arcs along this angle, so no set needs its own sort).
std::vector<std::vector<int>> arcs(const WorkGraph& g, const std::vector<int>& vertices,
                                   const std::vector<double>& angle,
                                   const std::vector<int>& by_phase, int first, int count,
                                   long long max_block, int rotations, std::vector<int>& part,
                                   std::vector<int>& mark, int stamp) {
  const double two_pi = 2.0 * std::acos(-1.0);
  const double width = two_pi / count;
  for (int v : vertices) mark[v] = stamp;
  std::vector<std::pair<double, int>> events;
  events.reserve(vertices.size());
  std::vector<long long> weight(static_cast<std::size_t>(count), 0);
  for (int v : vertices) {
    const double a = std::fmod(angle[v], two_pi);
    const int b = std::min(count - 1, static_cast<int>(a / width));
    part[v] = first + b;
    weight[b] += g.vw[v];
  }
  for (int v : by_phase)
    if (mark[v] == stamp) {
      const double a = std::fmod(angle[v], two_pi);
      events.emplace_back(a - (part[v] - first) * width, v);
    }
  std::vector<int> start(vertices.size());
  for (std::size_t q = 0; q < vertices.size(); ++q) start[q] = part[vertices[q]];
  long long cut = 0;
  for (int v : vertices)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (u < v && mark[u] == stamp && part[u] != part[v]) cut += g.ew[e];
    }
  auto feasible = [&] { return *std::max_element(weight.begin(), weight.end()) <= max_block; };
  std::vector<std::tuple<long long, double, std::size_t>> states;  // cut, rotation, events
  if (feasible()) states.emplace_back(cut, 0.0, 0);
  for (std::size_t q = 0; q < events.size(); ++q) {
    const int v = events[q].second;
    const int from = part[v] - first;
    const int to = first + (from + count - 1) % count;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (mark[u] != stamp) continue;
      cut += static_cast<long long>(g.ew[e]) *
             (static_cast<int>(part[u] != to) - static_cast<int>(part[u] != part[v]));
    }
    weight[from] -= g.vw[v];
    weight[to - first] += g.vw[v];
    part[v] = to;
    const bool last_at_this_angle = q + 1 == events.size() || events[q + 1].first > events[q].first;
    if (last_at_this_angle && feasible()) states.emplace_back(cut, events[q].first, q + 1);
  }
  auto by_cut = [](const auto& x, const auto& y) { return std::get<0>(x) < std::get<0>(y); };
  if (rotations == 1 && !states.empty())
    states = {*std::min_element(states.begin(), states.end(), by_cut)};  // the first best
  std::stable_sort(states.begin(), states.end(), by_cut);
  std::vector<std::size_t> chosen;
  std::vector<double> chosen_t;
  for (const auto& st : states) {
    if (static_cast<int>(chosen.size()) >= rotations) break;
    bool near = false;
    for (double t : chosen_t) {
      const double d = std::fabs(t - std::get<1>(st));
      near = near || std::min(d, width - d) < 0.1 * width;
    }
    if (near) continue;
    chosen.push_back(std::get<2>(st));
    chosen_t.push_back(std::get<1>(st));
  }
  std::vector<std::vector<int>> out;
  std::vector<int> pos(static_cast<std::size_t>(g.n));
  for (std::size_t q = 0; q < vertices.size(); ++q) pos[vertices[q]] = static_cast<int>(q);
  for (std::size_t applied : chosen) {
    std::vector<int> blocks = start;
    for (std::size_t q = 0; q < applied; ++q) {
      int& b = blocks[pos[events[q].second]];
      b = first + (b - first + count - 1) % count;
    }
    out.push_back(std::move(blocks));
  }
  return out;
}

std::vector<int> sorted_by(const std::vector<int>& vertices, const std::vector<double>& key) {
  std::vector<int> order = vertices;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

// The first `share` of the weight of `order` (a prefix), as a vertex list.
std::pair<std::vector<int>, std::vector<int>> split_prefix(const WorkGraph& g,
                                                           const std::vector<int>& order, int num,
                                                           int den) {
  long long total = 0;
  for (int v : order) total += g.vw[v];
  std::pair<std::vector<int>, std::vector<int>> sides;
  long long acc = 0;
  for (int v : order) {
    if (acc * den < total * num)
      sides.first.push_back(v);
    else
      sides.second.push_back(v);
    acc += g.vw[v];
  }
  return sides;
}

// Recursive coordinate bisection in the (eigenvalue-scaled) embedding: each step cuts along
// the coordinate with the widest spread among its vertices, in proportion to the block counts.
void rcb(const WorkGraph& g, const std::vector<std::vector<double>>& coords,
         const std::vector<int>& vertices, int first, int count, std::vector<int>& part) {
  if (count == 1) {
    for (int v : vertices) part[v] = first;
    return;
  }
  int best = 0;
  double best_spread = -1.0;
  for (std::size_t j = 0; j < coords.size(); ++j) {
    double mean = 0.0, sq = 0.0;
    for (int v : vertices) mean += coords[j][v];
    mean /= static_cast<double>(vertices.size());
    for (int v : vertices) sq += (coords[j][v] - mean) * (coords[j][v] - mean);
    if (sq > best_spread) {
      best_spread = sq;
      best = static_cast<int>(j);
    }
  }
  const int left = count / 2;
  auto sides = split_prefix(g, sorted_by(vertices, coords[best]), left, count);
  rcb(g, coords, sides.first, first, left, part);
  rcb(g, coords, sides.second, first + left, count - left, part);
}

}  // namespace

std::vector<SpectralLayout> spectral_layouts(const WorkGraph& g, int k, long long max_block,
                                             const SpectralLayoutOptions& options) {
  options.validate();
  std::vector<SpectralLayout> out;
  if (k < 2 || k > options.max_parts || g.n < k + 2 || g.n > options.max_vertices) return out;
  const int m = std::min(options.eigenvectors, g.n - 2);
  Eigen::VectorXd lambdas;
  const Eigen::MatrixXd u = embedding(g, m, options, &lambdas);
  if (u.cols() == 0) return out;
  const int n = g.n;
  std::vector<std::vector<double>> coord(static_cast<std::size_t>(m), std::vector<double>(n));
  for (int j = 0; j < m; ++j)
    for (int v = 0; v < n; ++v) coord[j][v] = u(v, j);
  std::vector<int> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  // Keeps the max_layouts layouts with the smallest cut (ties: the earlier one).
  std::vector<long long> cuts;
  auto add = [&](std::string name, const std::vector<int>& layout,
                 std::vector<CyclicSide> sides = {}) {
    const long long cut = edge_cut(g, layout);
    if (static_cast<int>(out.size()) >= options.max_layouts) {
      const auto worst = std::max_element(cuts.begin(), cuts.end()) - cuts.begin();
      if (cut >= cuts[worst]) return;
      out.erase(out.begin() + worst);
      cuts.erase(cuts.begin() + worst);
    }
    out.push_back({std::move(name), layout, cut, std::move(sides)});
    cuts.push_back(cut);
  };
  auto uname = [](int j) { return "u" + std::to_string(j + 1); };
  std::vector<int> part(static_cast<std::size_t>(n), 0);

  // Sort keys: every coordinate, and the angle around the origin of every coordinate plane (a
  // ring, e.g. a torus or a cylinder's circumference, embeds as a circle in the plane of its
  // two degenerate eigenvectors). Angle keys are cut into arcs at their best rotation.
  const double two_pi = 2.0 * std::acos(-1.0);
  struct Key {
    std::string name;
    int i = 0, j = -1;  // coordinate i, or the plane (i, j)
  };
  std::vector<Key> keys;
  for (int i = 0; i < m; ++i) keys.push_back({uname(i), i, -1});
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j) keys.push_back({"angle " + uname(i) + uname(j), i, j});
  auto values = [&](const Key& key) {
    if (key.j < 0) return coord[key.i];
    std::vector<double> angle(static_cast<std::size_t>(n));
    for (int v = 0; v < n; ++v) angle[v] = std::atan2(coord[key.j][v], coord[key.i][v]) + two_pi;
    return angle;
  };
  // Arc rotations count vertices, which matches weights only on a graph of unit weights.
  const bool unit = std::all_of(g.vw.begin(), g.vw.end(), [](int w) { return w == 1; });
  std::vector<int> mark(static_cast<std::size_t>(n), -1);
  int stamp = 0;
  // The ways to deal `order` out to blocks first..first+count-1 along a key (each a block per
  // entry of `order`): slabs of equal weight for a coordinate; for an angle, arcs of equal angle
  // at their best few rotations, or (if none is within the bound) arcs of equal size at their
  // best rotation.
  std::vector<std::vector<double>> angles;  // per key (empty for coordinates)
  // Per (key, count): all vertices sorted by their angle's phase within an arc (see arcs()).
  std::vector<std::vector<int>> phase_orders((keys.size()) * static_cast<std::size_t>(k + 1));
  auto choices = [&](const Key& key, const std::vector<int>& order, int first, int count) {
    std::vector<std::vector<int>> out;
    auto take = [&] {
      std::vector<int> blocks(order.size());
      for (std::size_t q = 0; q < order.size(); ++q) blocks[q] = part[order[q]];
      out.push_back(std::move(blocks));
    };
    if (key.j < 0) {
      deal(g, order, first, count, part);
      take();
      return out;
    }
    const std::size_t q = static_cast<std::size_t>(&key - keys.data());
    std::vector<int>& by_phase = phase_orders[q * static_cast<std::size_t>(k + 1) + count];
    if (by_phase.empty()) {
      const double width = two_pi / count;
      std::vector<double> phase(static_cast<std::size_t>(n));
      for (int v = 0; v < n; ++v) {
        const double a = std::fmod(angles[q][v], two_pi);
        phase[v] = a - std::min(count - 1, static_cast<int>(a / width)) * width;
      }
      by_phase = sorted_by(all, phase);
    }
    for (auto& blocks : arcs(g, order, angles[q], by_phase, first, count, max_block,
                             options.rotations, part, mark, stamp++))
      out.push_back(std::move(blocks));
    if (out.empty()) {
      if (unit)
        deal_cyclic(g, order, first, count, part, mark, stamp++);
      else
        deal(g, order, first, count, part);
      take();
    }
    return out;
  };
  auto apply = [&](const std::vector<int>& order, const std::vector<int>& blocks) {
    for (std::size_t q = 0; q < order.size(); ++q) part[order[q]] = blocks[q];
  };
  std::vector<std::vector<int>> sorted;
  for (const Key& key : keys) {
    angles.push_back(key.j < 0 ? std::vector<double>() : values(key));
    sorted.push_back(sorted_by(all, values(key)));
  }
  // One level: k slabs or arcs.
  for (std::size_t q = 0; q < keys.size(); ++q) {
    int c = 0;
    for (const auto& blocks : choices(keys[q], sorted[q], 0, k)) {
      apply(sorted[q], blocks);
      std::vector<CyclicSide> ring;
      if (keys[q].j >= 0) ring.push_back({sorted[q], 0, k});
      add(keys[q].name + " #" + std::to_string(c++), part, std::move(ring));
    }
  }
  // Two levels ("a + b"): the first a/k of the weight along one key in a slabs or arcs of a
  // second key, the rest in k - a of them (e.g. a 3 + 2 layout of a cylinder: 3/5 of its length
  // cut into 3 sectors around it, the rest into 2). The second key uses other coordinates than
  // the first.
  auto disjoint = [](const Key& a, const Key& b) {
    return a.i != b.i && a.i != b.j && (a.j < 0 || (a.j != b.i && a.j != b.j));
  };
  std::vector<char> in_first(static_cast<std::size_t>(n), 0);
  for (std::size_t q1 = 0; q1 < keys.size(); ++q1)
    for (std::size_t q2 = 0; q2 < keys.size(); ++q2) {
      if (!disjoint(keys[q1], keys[q2])) continue;
      for (int a = 1; a < k; ++a) {
        auto sides = split_prefix(g, sorted[q1], a, k);
        // Both sides in the order of the second key (a filter of its sorted order).
        for (int v : sides.first) in_first[v] = 1;
        for (int v : sides.second) in_first[v] = 0;
        sides.first.clear();
        sides.second.clear();
        for (int v : sorted[q2]) (in_first[v] ? sides.first : sides.second).push_back(v);
        const auto first_side = choices(keys[q2], sides.first, 0, a);
        const auto second_side = choices(keys[q2], sides.second, a, k - a);
        for (std::size_t c1 = 0; c1 < first_side.size(); ++c1)
          for (std::size_t c2 = 0; c2 < second_side.size(); ++c2) {
            apply(sides.first, first_side[c1]);
            apply(sides.second, second_side[c2]);
            std::vector<CyclicSide> ring;
            if (keys[q2].j >= 0) ring = {{sides.first, 0, a}, {sides.second, a, k - a}};
            add(std::to_string(a) + "+" + std::to_string(k - a) + " " + keys[q1].name + " / " +
                    keys[q2].name + " #" + std::to_string(c1) + std::to_string(c2),
                part, std::move(ring));
          }
      }
    }
  // Recursive coordinate bisection, coordinates scaled by 1 / sqrt(lambda) (the large-scale
  // directions get the larger spread, as in a spectral drawing of the graph).
  std::vector<std::vector<double>> scaled = coord;
  for (int j = 0; j < m; ++j) {
    const double s = 1.0 / std::sqrt(std::max(lambdas(j), 1e-12));
    for (double& x : scaled[j]) x *= s;
  }
  rcb(g, scaled, all, 0, k, part);
  add("rcb", part);
  return out;
}

namespace {

// Rebalanced and FM-refined under ub (cheap), as both halves below refine their layouts.
std::vector<int> fm_polished(const WorkGraph& g, int k, const std::vector<long long>& ub,
                             const CycleParams& cycle, std::vector<int> p, long long* cut,
                             Rng& rng) {
  rebalance(g, k, p, ub);
  *cut = kway_fm(g, k, p, ub, cycle.fm, rng);
  return p;
}

}  // namespace

std::vector<RefinedLayout> fm_refined_layouts(const WorkGraph& g, int k,
                                              const std::vector<long long>& ub,
                                              const SpectralLayoutOptions& options,
                                              const CycleParams& cycle, Rng& rng) {
  std::vector<RefinedLayout> cands;
  for (auto& layout : spectral_layouts(g, k, *std::min_element(ub.begin(), ub.end()), options)) {
    long long cut = 0;
    std::vector<int> p = fm_polished(g, k, ub, cycle, layout.part, &cut, rng);
    cands.push_back({cut, std::move(p), std::move(layout)});
  }
  std::stable_sort(cands.begin(), cands.end(),
                   [](const auto& a, const auto& b) { return a.cut < b.cut; });
  return cands;
}

std::vector<std::vector<int>> finished_layouts(const WorkGraph& g, int k,
                                               const std::vector<long long>& ub,
                                               const SpectralLayoutOptions& options,
                                               const CycleParams& cycle,
                                               std::vector<RefinedLayout> cands, int keep, Rng& rng,
                                               long long worst_useful) {
  std::vector<std::vector<int>> out;
  if (keep <= 0) return out;
  if (worst_useful >= 0)
    while (!cands.empty() && cands.back().cut > worst_useful) cands.pop_back();
  // Rotation polish (see SpectralLayoutOptions::polish), one set of arcs after the other.
  int polished_count = 0;
  for (RefinedLayout& cand : cands) {
    if (polished_count >= options.polish) break;
    if (cand.layout.sides.empty()) continue;  // slabs only: nothing to rotate
    ++polished_count;
    std::vector<int> base = cand.layout.part;
    for (const CyclicSide& side : cand.layout.sides) {
      const int ns = static_cast<int>(side.order.size());
      const int arc = std::max(1, ns / side.count);
      const int steps = std::min(arc, options.rotation_steps);
      int best_s = -1;
      for (int step = 0; step < steps; ++step) {
        const int shift = static_cast<int>(static_cast<long long>(step) * arc / steps);
        std::vector<int> trial = base;
        for (int q = 0; q < ns; ++q)
          trial[side.order[(q + shift) % ns]] =
              side.first + static_cast<int>(static_cast<long long>(q) * side.count / ns);
        long long cut = 0;
        std::vector<int> p = fm_polished(g, k, ub, cycle, trial, &cut, rng);
        if (cut < cand.cut) {
          cand.cut = cut;
          cand.part = std::move(p);
          best_s = shift;
        }
      }
      if (best_s >= 0)
        for (int q = 0; q < ns; ++q)
          base[side.order[(q + best_s) % ns]] =
              side.first + static_cast<int>(static_cast<long long>(q) * side.count / ns);
    }
  }
  std::stable_sort(cands.begin(), cands.end(),
                   [](const auto& a, const auto& b) { return a.cut < b.cut; });
  for (auto& c : cands) {
    if (static_cast<int>(out.size()) >= keep) break;
    bool duplicate = false;
    for (const auto& o : out) duplicate = duplicate || o == c.part;
    if (duplicate) continue;
    std::vector<int> p = guided_cycle(g, k, ub, c.part, c.part, cycle, rng);
    out.push_back(edge_cut(g, p) <= c.cut ? std::move(p) : std::move(c.part));
  }
  return out;
}

std::vector<std::vector<int>> refined_spectral_layouts(const WorkGraph& g, int k,
                                                       const std::vector<long long>& ub,
                                                       const SpectralLayoutOptions& options,
                                                       const CycleParams& cycle, int keep, Rng& rng,
                                                       long long worst_useful) {
  if (keep <= 0) return {};
  return finished_layouts(g, k, ub, options, cycle,
                          fm_refined_layouts(g, k, ub, options, cycle, rng), keep, rng,
                          worst_useful);
}

}  // namespace tessera::partition_detail
