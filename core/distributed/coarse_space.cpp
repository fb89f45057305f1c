#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <stdexcept>
#include <string>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <unordered_map>

#include "distributed/coarse_problem.hpp"

namespace tessera {

namespace {

using Mat = Eigen::MatrixXd;
using Edges = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
using Weights = std::vector<std::pair<int, double>>;  // aggregate -> weight, ascending

// Adjacency lists (CSR) of the edges kept by `keep`, self-loops left out, parallel edges kept
// (a pose's degree counts each measurement).
struct Adjacency {
  std::vector<std::size_t> start;
  std::vector<std::size_t> next;
  template <class Keep>
  Adjacency(std::size_t n, const Edges& edges, Keep keep) : start(n + 1, 0) {
    for (const auto& [i, j] : edges)
      if (i != j && keep(i, j)) ++start[i + 1], ++start[j + 1];
    for (std::size_t k = 0; k < n; ++k) start[k + 1] += start[k];
    next.resize(start[n]);
    std::vector<std::size_t> at(start.begin(), start.end() - 1);
    for (const auto& [i, j] : edges)
      if (i != j && keep(i, j)) {
        next[at[i]++] = j;
        next[at[j]++] = i;
      }
  }
};

// Splits each block's own graph into about block_aggregates() pieces: seeds by farthest-point BFS
// (the first seed the pose farthest from the block's first pose), every pose to its nearest seed in
// hops (ties to the earlier seed); a part of the block that no seed reaches gets a piece of its
// own.
void grow_aggregates(CoarseSpace& s, const Adjacency& inside,
                     const std::vector<std::vector<std::size_t>>& block_poses,
                     const CoarseOptions& options) {
  const std::size_t n = s.owner.size();
  s.aggregate.assign(n, -1);
  std::vector<int> dist(n, -1);
  std::deque<std::size_t> queue;
  auto bfs = [&](const std::vector<std::size_t>& mine, const std::vector<std::size_t>& seeds) {
    for (std::size_t i : mine) dist[i] = -1;
    for (std::size_t v : seeds) {
      dist[v] = 0;
      queue.push_back(v);
    }
    while (!queue.empty()) {
      const std::size_t u = queue.front();
      queue.pop_front();
      for (std::size_t e = inside.start[u]; e < inside.start[u + 1]; ++e)
        if (dist[inside.next[e]] < 0) {
          dist[inside.next[e]] = dist[u] + 1;
          queue.push_back(inside.next[e]);
        }
    }
  };
  // The pose farthest from the seeds (unreached counts as farthest), lowest id on ties.
  auto farthest = [&](const std::vector<std::size_t>& mine, int* how_far) {
    std::size_t best = mine.front();
    int far = -1;
    for (std::size_t i : mine) {
      const int di = dist[i] < 0 ? (1 << 30) : dist[i];
      if (di > far) {
        far = di;
        best = i;
      }
    }
    *how_far = far;
    return best;
  };
  for (int b = 0; b < s.num_blocks; ++b) {
    const auto& mine = block_poses[static_cast<std::size_t>(b)];
    const int k = block_aggregates(options, mine.size());
    std::vector<std::size_t> seeds;
    int far = 0;
    bfs(mine, {mine.front()});
    seeds.push_back(farthest(mine, &far));
    while (static_cast<int>(seeds.size()) < k) {
      bfs(mine, seeds);
      const std::size_t v = farthest(mine, &far);
      if (far <= 0) break;  // every pose is a seed already
      seeds.push_back(v);
    }
    // Label by a multi-source BFS; then each unreached part of the block its own piece.
    const int first = s.num_aggregates;
    for (std::size_t q = 0; q < seeds.size(); ++q) {
      s.aggregate[seeds[q]] = first + static_cast<int>(q);
      queue.push_back(seeds[q]);
    }
    int count = static_cast<int>(seeds.size());
    std::size_t scan = 0;
    for (;;) {
      while (!queue.empty()) {
        const std::size_t u = queue.front();
        queue.pop_front();
        for (std::size_t e = inside.start[u]; e < inside.start[u + 1]; ++e)
          if (s.aggregate[inside.next[e]] < 0) {
            s.aggregate[inside.next[e]] = s.aggregate[u];
            queue.push_back(inside.next[e]);
          }
      }
      while (scan < mine.size() && s.aggregate[mine[scan]] >= 0) ++scan;
      if (scan == mine.size()) break;
      s.aggregate[mine[scan]] = first + count++;
      queue.push_back(mine[scan]);
    }
    s.num_aggregates += count;
    s.aggregate_block.insert(s.aggregate_block.end(), static_cast<std::size_t>(count), b);
  }
}

// w <- (1 - omega) w + omega D^-1 A w, `steps` times, from the pieces' indicators.
std::vector<Weights> smooth_weights(const CoarseSpace& s, const Adjacency& all, int steps,
                                    double omega) {
  const std::size_t n = s.owner.size();
  std::vector<Weights> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = {{s.aggregate[i], 1.0}};
  std::unordered_map<int, double> acc;
  for (int step = 0; step < steps; ++step) {
    std::vector<Weights> nw(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t deg = all.start[i + 1] - all.start[i];
      if (deg == 0) {
        nw[i] = w[i];
        continue;
      }
      acc.clear();
      for (const auto& [a, v] : w[i]) acc[a] += (1.0 - omega) * v;
      const double share = omega / static_cast<double>(deg);
      for (std::size_t e = all.start[i]; e < all.start[i + 1]; ++e)
        for (const auto& [a, v] : w[all.next[e]]) acc[a] += share * v;
      nw[i].assign(acc.begin(), acc.end());
      std::sort(nw[i].begin(), nw[i].end());
    }
    w.swap(nw);
  }
  return w;
}

}  // namespace

bool CoarseSpace::sums_edge(int agent, std::size_t i, std::size_t j) const {
  const int a = owner[i], b = owner[j];
  return a == b ? a == agent : std::min(a, b) == agent;
}

bool CoarseSpace::rigid_invariant(std::size_t i, std::size_t j) const {
  return weight_start[i + 1] - weight_start[i] == 1 && weight_start[j + 1] - weight_start[j] == 1 &&
         weight_aggregate[weight_start[i]] == weight_aggregate[weight_start[j]];
}

std::size_t CoarseSpace::bytes() const {
  return aggregate_block.capacity() * sizeof(int) + owner.capacity() * sizeof(int) +
         aggregate.capacity() * sizeof(int) + weight_start.capacity() * sizeof(std::size_t) +
         weight_aggregate.capacity() * sizeof(int) + weight.capacity() * sizeof(double) +
         pair_start.capacity() * sizeof(std::size_t) +
         pairs.capacity() * sizeof(std::pair<int, int>);
}

CoarseSpace make_coarse_space(std::size_t num_poses, const Edges& edges,
                              const std::vector<int>& assignment, const CoarseOptions& options) {
  options.validate();
  if (assignment.size() != num_poses)
    throw std::invalid_argument("make_coarse_space: assignment of the wrong size");
  CoarseSpace s;
  s.owner = assignment;
  for (int b : assignment) s.num_blocks = std::max(s.num_blocks, b + 1);
  std::vector<std::vector<std::size_t>> block_poses(static_cast<std::size_t>(s.num_blocks));
  for (std::size_t i = 0; i < num_poses; ++i)
    block_poses[static_cast<std::size_t>(assignment[i])].push_back(i);
  for (const auto& p : block_poses)
    if (p.empty()) throw std::invalid_argument("make_coarse_space: empty block");
  for (const auto& [i, j] : edges)
    if (i >= num_poses || j >= num_poses)
      throw std::invalid_argument("make_coarse_space: edge out of range");
  {
    const Adjacency inside(num_poses, edges, [&](std::uint32_t i, std::uint32_t j) {
      return assignment[i] == assignment[j];
    });
    grow_aggregates(s, inside, block_poses, options);
  }
  {
    const Adjacency all(num_poses, edges, [](std::uint32_t, std::uint32_t) { return true; });
    const std::vector<Weights> w =
        smooth_weights(s, all, options.smoothing_steps, options.smoothing_weight);
    s.weight_start.assign(num_poses + 1, 0);
    for (std::size_t i = 0; i < num_poses; ++i)
      s.weight_start[i + 1] = s.weight_start[i] + w[i].size();
    // Every agent keeps these whole-graph lists through the run: sized once, not grown by
    // doubling (which left up to half their capacity unused).
    s.weight_aggregate.reserve(s.weight_start[num_poses]);
    s.weight.reserve(s.weight_start[num_poses]);
    for (std::size_t i = 0; i < num_poses; ++i) {
      for (const auto& [a, v] : w[i]) {
        s.weight_aggregate.push_back(a);
        s.weight.push_back(v);
      }
    }
  }
  // Each agent's pairs: every pair of pieces some edge it sums couples.
  std::vector<std::vector<std::pair<int, int>>> pairs(static_cast<std::size_t>(s.num_blocks));
  std::vector<int> support;
  for (const auto& [i, j] : edges) {
    if (i == j || s.rigid_invariant(i, j)) continue;
    const int agent = s.owner[i] == s.owner[j] ? s.owner[i] : std::min(s.owner[i], s.owner[j]);
    support.clear();
    for (std::size_t e = s.weight_start[i]; e < s.weight_start[i + 1]; ++e)
      support.push_back(s.weight_aggregate[e]);
    for (std::size_t e = s.weight_start[j]; e < s.weight_start[j + 1]; ++e)
      support.push_back(s.weight_aggregate[e]);
    std::sort(support.begin(), support.end());
    support.erase(std::unique(support.begin(), support.end()), support.end());
    auto& p = pairs[static_cast<std::size_t>(agent)];
    for (std::size_t x = 0; x < support.size(); ++x)
      for (std::size_t y = x; y < support.size(); ++y) p.emplace_back(support[x], support[y]);
  }
  s.pair_start.assign(static_cast<std::size_t>(s.num_blocks) + 1, 0);
  for (int a = 0; a < s.num_blocks; ++a) {
    auto& p = pairs[static_cast<std::size_t>(a)];
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    s.pairs.insert(s.pairs.end(), p.begin(), p.end());
    s.pair_start[static_cast<std::size_t>(a) + 1] = s.pairs.size();
  }
  return s;
}

CoarseSpace make_coarse_space(std::size_t num_poses, const std::vector<Measurement>& measurements,
                              const std::vector<int>& assignment, const CoarseOptions& options) {
  Edges edges;
  edges.reserve(measurements.size());
  for (const Measurement& m : measurements)
    edges.emplace_back(static_cast<std::uint32_t>(m.i), static_cast<std::uint32_t>(m.j));
  return make_coarse_space(num_poses, edges, assignment, options);
}

SmoothedCoarseTerms::SmoothedCoarseTerms(const CoarseSpace& space, int id, int d,
                                         const std::vector<std::size_t>& owned,
                                         const std::vector<std::size_t>& neighbours,
                                         const std::vector<Measurement>& measurements)
    : space_(space), id_(id), d_(d) {
  std::unordered_map<std::size_t, std::size_t> own_slot, neighbour_slot;
  for (std::size_t k = 0; k < owned.size(); ++k) own_slot[owned[k]] = k;
  for (std::size_t k = 0; k < neighbours.size(); ++k) neighbour_slot[neighbours[k]] = k;
  auto slot = [&](std::size_t v, bool* own) {
    auto it = own_slot.find(v);
    if (it != own_slot.end()) {
      *own = true;
      return it->second;
    }
    *own = false;
    auto jt = neighbour_slot.find(v);
    if (jt == neighbour_slot.end())
      throw std::logic_error("SmoothedCoarseTerms: an edge it sums has an unknown end");
    return jt->second;
  };
  const auto pair_begin = space.pairs.begin() + static_cast<std::ptrdiff_t>(
                                                    space.pair_start[static_cast<std::size_t>(id)]);
  const auto pair_end =
      space.pairs.begin() +
      static_cast<std::ptrdiff_t>(space.pair_start[static_cast<std::size_t>(id) + 1]);
  std::vector<int> support;
  for (const Measurement& m : measurements) {
    if (m.i == m.j || m.i >= space.owner.size() || m.j >= space.owner.size()) continue;
    if (!space.sums_edge(id, m.i, m.j) || space.rigid_invariant(m.i, m.j)) continue;
    if (!own_slot.count(m.i) && !own_slot.count(m.j)) continue;  // not ours (whole-graph list)
    Edge e;
    e.i_slot = slot(m.i, &e.i_own);
    e.j_slot = slot(m.j, &e.j_own);
    e.R = m.R;
    e.t = m.t;
    e.kappa = m.kappa;
    e.tau = m.tau;
    // The merge of the two ends' ascending weight lists, and the agent's pair of each two of
    // its pieces.
    e.piece_begin = pieces_.size();
    support.clear();
    const std::size_t i0 = space.weight_start[m.i], i1 = space.weight_start[m.i + 1];
    const std::size_t j0 = space.weight_start[m.j], j1 = space.weight_start[m.j + 1];
    std::size_t x = i0, y = j0;
    while (x < i1 || y < j1) {
      const int ax = x < i1 ? space.weight_aggregate[x] : INT32_MAX;
      const int ay = y < j1 ? space.weight_aggregate[y] : INT32_MAX;
      const int a = std::min(ax, ay);
      Piece piece{ay == a, ax == a, 0.0, 0.0};
      if (piece.at_j) piece.w_j = space.weight[y++];
      if (piece.at_i) piece.w_i = space.weight[x++];
      pieces_.push_back(piece);
      support.push_back(a);
    }
    e.piece_end = pieces_.size();
    max_pieces_ = std::max(max_pieces_, e.piece_end - e.piece_begin);
    e.pair_begin = pair_index_.size();
    for (std::size_t p = 0; p < support.size(); ++p)
      for (std::size_t q = p; q < support.size(); ++q) {
        const auto it =
            std::lower_bound(pair_begin, pair_end, std::make_pair(support[p], support[q]));
        if (it == pair_end || *it != std::make_pair(support[p], support[q]))
          throw std::logic_error("SmoothedCoarseTerms: a pair missing from the space");
        pair_index_.push_back(static_cast<std::size_t>(it - pair_begin));
      }
    edges_.push_back(std::move(e));
  }
}

std::size_t SmoothedCoarseTerms::bytes() const {
  std::size_t b = edges_.capacity() * sizeof(Edge) + pieces_.capacity() * sizeof(Piece) +
                  pair_index_.capacity() * sizeof(std::size_t);
  for (const Edge& e : edges_)
    b += static_cast<std::size_t>(e.R.size() + e.t.size()) * sizeof(double);
  return b;
}

std::vector<double> SmoothedCoarseTerms::compute(const Eigen::MatrixXd& X,
                                                 const Eigen::MatrixXd& Xn) const {
  const int r = static_cast<int>(X.rows());
  const int s = r + 1;
  const int w = d_ + 1;
  const std::size_t first = space_.pair_start[static_cast<std::size_t>(id_)];
  const std::size_t count = space_.pair_start[static_cast<std::size_t>(id_) + 1] - first;
  double mask = 0.0;
  const std::vector<int> rows = coarse_rows_in_use(X, Xn, mask);
  const std::size_t m = rows.size();
  // The terms are summed straight into their packed layout, on the used rows only: the other
  // rows of Q are never sent, and each packed entry gets the same sums in the same order as
  // the full Q would (so the terms do not change by a bit).
  std::vector<std::size_t> offset(count);
  std::size_t total = 1;
  for (std::size_t k = 0; k < count; ++k) {
    offset[k] = total;
    const auto& pair = space_.pairs[first + k];
    total += pair.first == pair.second ? m * (m + 1) / 2 : m * m;
  }
  std::vector<double> out(total, 0.0);
  out[0] = mask;
  Mat A = Mat::Zero(s, w), B = Mat::Zero(s, w);
  // C_p on the used rows, per piece p of the edge: m x w, column-major.
  const std::size_t cm = m * static_cast<std::size_t>(w);
  std::vector<double> C(max_pieces_ * cm);
  for (const Edge& e : edges_) {
    const auto Pi = e.i_own ? X.middleCols(static_cast<Eigen::Index>(w * e.i_slot), w)
                            : Xn.middleCols(static_cast<Eigen::Index>(w * e.i_slot), w);
    const auto Pj = e.j_own ? X.middleCols(static_cast<Eigen::Index>(w * e.j_slot), w)
                            : Xn.middleCols(static_cast<Eigen::Index>(w * e.j_slot), w);
    const double sk = std::sqrt(e.kappa), st = std::sqrt(e.tau);
    // The residual after the blend is sum_alpha Z_alpha C_alpha, C_alpha = w_j,alpha A -
    // w_i,alpha B, with A, B as in CoarseTerms (target j, transported source i).
    lift_target(A, Pj, d_, sk, st);
    lift_source(B, Pi, e.R, e.t, d_, sk, st);
    const std::size_t np = e.piece_end - e.piece_begin;
    for (std::size_t p = 0; p < np; ++p) {
      const Piece& piece = pieces_[e.piece_begin + p];
      double* Cp = C.data() + p * cm;
      for (int k = 0; k < w; ++k)
        for (std::size_t a = 0; a < m; ++a) {
          double c = 0.0;
          if (piece.at_j) c += piece.w_j * A(rows[a], k);
          if (piece.at_i) c -= piece.w_i * B(rows[a], k);
          Cp[a + m * static_cast<std::size_t>(k)] = c;
        }
    }
    // Q_pq += C_p C_q^T, entry by entry: each a sum over the w columns from 0.
    std::size_t pair = e.pair_begin;
    for (std::size_t p = 0; p < np; ++p)
      for (std::size_t q = p; q < np; ++q, ++pair) {
        const double* Cp = C.data() + p * cm;
        const double* Cq = C.data() + q * cm;
        double* o = out.data() + offset[pair_index_[pair]];
        for (std::size_t j = 0; j < m; ++j)
          for (std::size_t i = 0; i < (p == q ? j + 1 : m); ++i) {
            double acc = 0.0;
            for (std::size_t k = 0; k < static_cast<std::size_t>(w); ++k)
              acc += Cp[i + m * k] * Cq[j + m * k];
            *o++ += acc;
          }
      }
  }
  return out;
}

CoarseResult solve_smoothed_coarse(const CoarseSpace& space, int r,
                                   const std::vector<const std::vector<double>*>& terms,
                                   const CoarseOptions& options) {
  const int N = space.num_blocks;
  const int s = r + 1;
  check_coarse_term_vectors(terms.size(), N);
  CoarseMatrix Q;
  Q.diag.assign(static_cast<std::size_t>(space.num_aggregates), Mat::Zero(s, s));
  Q.off.resize(static_cast<std::size_t>(space.num_aggregates));
  // Summed in agent-id order, so every agent assembles bit-identical blocks.
  for (int a = 0; a < N; ++a) {
    const std::vector<double>& t = *terms[static_cast<std::size_t>(a)];
    const std::vector<int> rows = coarse_term_rows(t, r, a);
    const std::size_t m = rows.size();
    const std::size_t p0 = space.pair_start[static_cast<std::size_t>(a)];
    const std::size_t p1 = space.pair_start[static_cast<std::size_t>(a) + 1];
    std::size_t expected = 1;
    for (std::size_t k = p0; k < p1; ++k)
      expected += space.pairs[k].first == space.pairs[k].second ? m * (m + 1) / 2 : m * m;
    check_coarse_term_size(t, expected, a);
    std::size_t at = 1;
    for (std::size_t k = p0; k < p1; ++k) {
      const auto [alpha, beta] = space.pairs[k];
      if (alpha == beta) {
        add_packed_block(t, at, rows, true, Q.diag[static_cast<std::size_t>(alpha)]);
      } else {
        Mat M = Mat::Zero(s, s);
        add_packed_block(t, at, rows, false, M);
        auto& ab = Q.off[static_cast<std::size_t>(alpha)][beta];
        if (ab.size() == 0) ab = Mat::Zero(s, s);
        ab += M;
        auto& ba = Q.off[static_cast<std::size_t>(beta)][alpha];
        if (ba.size() == 0) ba = Mat::Zero(s, s);
        ba += M.transpose();
      }
    }
  }
  return solve_coarse_matrix(std::move(Q), r, options);
}

namespace {

// Moves X's poses and, when `V` is given, V's: a pose of V equal to X's (bit for bit; an
// inactive block has V = Y) gets X's moved pose without a second polar factor.
void move_blended(const CoarseSpace& space, const std::vector<Eigen::MatrixXd>& motions, int d,
                  const std::vector<std::size_t>& ids, Eigen::MatrixXd& X, Eigen::MatrixXd* V) {
  const Eigen::Index r = X.rows();
  const Eigen::Index w = d + 1;
  // Work space kept from pose to pose (the SVD reallocates nothing when the sizes repeat); the
  // arithmetic is polar_factor's, so the moved poses are the same to the bit.
  Mat M(r, r + 1), Y(r, d);
  Eigen::VectorXd p(r);
  Eigen::JacobiSVD<Mat> svd(r, d, Eigen::ComputeThinU | Eigen::ComputeThinV);
  auto move = [&](std::size_t e0, std::size_t e1, auto Xi) {
    Y.noalias() = M.leftCols(r) * Xi.leftCols(d);
    p.noalias() = M.leftCols(r) * Xi.col(d);
    p += M.col(r);
    // A blend of rotations is not one: back to the manifold by the polar factor (a single
    // rigid motion is orthogonal already and is kept bit for bit).
    if (e1 - e0 == 1) {
      Xi.leftCols(d) = Y;
    } else {
      svd.compute(Y, Eigen::ComputeThinU | Eigen::ComputeThinV);
      Xi.leftCols(d).noalias() = svd.matrixU() * svd.matrixV().transpose();
    }
    Xi.col(d) = p;
  };
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::size_t i = ids[k];
    const std::size_t e0 = space.weight_start[i], e1 = space.weight_start[i + 1];
    M.setZero();
    for (std::size_t e = e0; e < e1; ++e)
      M += space.weight[e] * motions[static_cast<std::size_t>(space.weight_aggregate[e])];
    auto Xi = X.middleCols(w * static_cast<Eigen::Index>(k), w);
    if (V == nullptr) {
      move(e0, e1, Xi);
      continue;
    }
    auto Vi = V->middleCols(w * static_cast<Eigen::Index>(k), w);
    // Columns of a column-major matrix: one contiguous run each, compared bit for bit.
    const bool same =
        std::memcmp(Vi.data(), Xi.data(), sizeof(double) * static_cast<std::size_t>(r * w)) == 0;
    move(e0, e1, Xi);
    if (same)
      Vi = Xi;
    else
      move(e0, e1, Vi);
  }
}

}  // namespace

void apply_blended_motions(const CoarseSpace& space, const std::vector<Eigen::MatrixXd>& motions,
                           int d, const std::vector<std::size_t>& ids, Eigen::MatrixXd& X) {
  move_blended(space, motions, d, ids, X, nullptr);
}

void apply_blended_motions(const CoarseSpace& space, const std::vector<Eigen::MatrixXd>& motions,
                           int d, const std::vector<std::size_t>& ids, Eigen::MatrixXd& X,
                           Eigen::MatrixXd& V) {
  if (V.rows() == X.rows() && V.cols() == X.cols()) {
    move_blended(space, motions, d, ids, X, &V);
  } else {
    move_blended(space, motions, d, ids, X, nullptr);
    move_blended(space, motions, d, ids, V, nullptr);
  }
}

}  // namespace tessera
