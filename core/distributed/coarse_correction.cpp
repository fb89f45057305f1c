#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/util/input_error.hpp>
#include <unordered_map>

#include "distributed/coarse_problem.hpp"
#include "distributed/nonzero_rows.hpp"

namespace tessera {

void CoarseOptions::validate() const {
  if (every < 1) throw InputError("CoarseOptions.every must be >= 1");
  if (max_iterations < 1) throw InputError("CoarseOptions.max_iterations must be >= 1");
  if (!(rel_tol >= 0 && rel_tol < 1)) throw InputError("CoarseOptions.rel_tol must be in [0, 1)");
  if (!(min_gain >= 0 && std::isfinite(min_gain)))
    throw InputError("CoarseOptions.min_gain must be finite and >= 0");
  if (aggregates < 1) throw InputError("CoarseOptions.aggregates must be >= 1");
  if (poses_per_aggregate < 0) throw InputError("CoarseOptions.poses_per_aggregate must be >= 0");
  if (smoothing_steps < 0 || smoothing_steps > 8)
    throw InputError("CoarseOptions.smoothing_steps must be in 0..8");
  if (!(smoothing_weight > 0 && smoothing_weight <= 1))
    throw InputError("CoarseOptions.smoothing_weight must be in (0, 1]");
}

int block_aggregates(const CoarseOptions& options, std::size_t block_poses) {
  if (options.poses_per_aggregate <= 0) return options.aggregates;
  const std::size_t per = static_cast<std::size_t>(options.poses_per_aggregate);
  const std::size_t pieces = (block_poses + per / 2) / per;
  return static_cast<int>(
      std::clamp<std::size_t>(pieces, 1, static_cast<std::size_t>(options.aggregates)));
}

const char* coarse_space_name(CoarseSpaceKind kind) {
  return kind == CoarseSpaceKind::kSmoothed ? "smoothed" : "blocks";
}

CoarseSpaceKind parse_coarse_space(const std::string& name) {
  if (name == "blocks") return CoarseSpaceKind::kBlocks;
  if (name == "smoothed") return CoarseSpaceKind::kSmoothed;
  throw InputError("coarse space '" + name + "' is not one of blocks, smoothed");
}

CoarseTerms::CoarseTerms(int id, int d, const BlockLayout& layout,
                         const std::vector<std::size_t>& owned,
                         const std::vector<std::size_t>& neighbours,
                         const std::vector<Measurement>& measurements)
    : d_(d), num_upper_(0) {
  const auto& adj = layout.adjacent[static_cast<std::size_t>(id)];
  std::vector<int> upper(adj.size(), -1);
  for (std::size_t k = 0; k < adj.size(); ++k)
    if (adj[k] > id) upper[k] = num_upper_++;
  std::unordered_map<std::size_t, std::size_t> own_slot, neighbour_slot;
  for (std::size_t k = 0; k < owned.size(); ++k) own_slot[owned[k]] = k;
  for (std::size_t k = 0; k < neighbours.size(); ++k) neighbour_slot[neighbours[k]] = k;
  for (const Measurement& m : measurements) {
    const bool source_own = own_slot.count(m.i) && neighbour_slot.count(m.j);
    const bool target_own = own_slot.count(m.j) && neighbour_slot.count(m.i);
    if (!source_own && !target_own) continue;  // inside the block (or not ours): rigid-invariant
    const std::size_t nb = source_own ? m.j : m.i;
    const int k = layout.adjacency_index(id, layout.owner[nb]);
    if (k < 0) throw std::logic_error("CoarseTerms: cut edge to a block that is not adjacent");
    edges_.push_back(Edge{own_slot[source_own ? m.i : m.j], neighbour_slot[nb], source_own,
                          upper[static_cast<std::size_t>(k)], m.R, m.t, m.kappa, m.tau});
  }
}

std::vector<double> CoarseTerms::compute(const Eigen::MatrixXd& X,
                                         const Eigen::MatrixXd& Xn) const {
  const int r = static_cast<int>(X.rows());
  const int s = r + 1;
  const int w = d_ + 1;
  // For a cut edge i -> j, the residual is Z_target A - Z_source B with
  // A = [sqrt(kappa) [Y_j; 0], sqrt(tau) [p_j; 1]] and B = [sqrt(kappa) [Y_i R; 0],
  // sqrt(tau) [p_i + Y_i t; 1]]. U is the own pose's matrix, W the neighbour's:
  // Q_aa += U U^T, Q_ab += -U W^T (a = this block, b = the neighbour's).
  Eigen::MatrixXd Qaa = Eigen::MatrixXd::Zero(s, s);
  std::vector<Eigen::MatrixXd> Qab(static_cast<std::size_t>(num_upper_),
                                   Eigen::MatrixXd::Zero(s, s));
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(s, w), W = Eigen::MatrixXd::Zero(s, w);
  for (const Edge& e : edges_) {
    const auto Po = X.middleCols(static_cast<Eigen::Index>(w * e.own_slot), w);
    const auto Pn = Xn.middleCols(static_cast<Eigen::Index>(w * e.neighbour_slot), w);
    const double sk = std::sqrt(e.kappa), st = std::sqrt(e.tau);
    if (e.own_is_source) {
      lift_source(U, Po, e.R, e.t, d_, sk, st);
      lift_target(W, Pn, d_, sk, st);
    } else {
      lift_target(U, Po, d_, sk, st);
      lift_source(W, Pn, e.R, e.t, d_, sk, st);
    }
    Qaa.noalias() += U * U.transpose();
    if (e.upper >= 0) Qab[static_cast<std::size_t>(e.upper)].noalias() -= U * W.transpose();
  }
  double mask = 0.0;
  const std::vector<int> rows = coarse_rows_in_use(X, Xn, mask);
  const std::size_t m = rows.size();
  std::vector<double> out;
  out.reserve(1 + m * (m + 1) / 2 + m * m * Qab.size());
  out.push_back(mask);
  append_packed_block(Qaa, rows, true, out);
  for (const auto& Q : Qab) append_packed_block(Q, rows, false, out);
  return out;
}

namespace {

using Mat = Eigen::MatrixXd;

double coarse_cost(const CoarseMatrix& Q, const std::vector<Mat>& Z) {
  double f = 0.0;
  for (std::size_t a = 0; a < Z.size(); ++a) {
    f += (Z[a] * Q.diag[a]).cwiseProduct(Z[a]).sum();
    for (const auto& [b, Qab] : Q.off[a])
      f += (Z[a] * Qab).cwiseProduct(Z[static_cast<std::size_t>(b)]).sum();
  }
  return f;
}

}  // namespace

CoarseResult solve_coarse(const BlockLayout& layout, int r,
                          const std::vector<const std::vector<double>*>& terms,
                          const CoarseOptions& options) {
  const int N = layout.num_blocks;
  const int s = r + 1;
  check_coarse_term_vectors(terms.size(), N);
  // Q_c in full (r+1) blocks from the agents' compact terms.
  CoarseMatrix Q;
  Q.diag.assign(static_cast<std::size_t>(N), Mat::Zero(s, s));
  Q.off.resize(static_cast<std::size_t>(N));
  for (int a = 0; a < N; ++a) {
    const std::vector<double>& t = *terms[static_cast<std::size_t>(a)];
    const std::vector<int> rows = coarse_term_rows(t, r, a);
    const std::size_t m = rows.size();
    std::vector<int> upper;
    for (int b : layout.adjacent[static_cast<std::size_t>(a)])
      if (b > a) upper.push_back(b);
    const std::size_t expected = 1 + m * (m + 1) / 2 + m * m * upper.size();
    check_coarse_term_size(t, expected, a);
    std::size_t at = 1;
    add_packed_block(t, at, rows, true, Q.diag[static_cast<std::size_t>(a)]);
    for (int b : upper) {
      Mat M = Mat::Zero(s, s);
      add_packed_block(t, at, rows, false, M);
      Q.off[static_cast<std::size_t>(b)][a] = M.transpose();
      Q.off[static_cast<std::size_t>(a)][b] = std::move(M);
    }
  }

  return solve_coarse_matrix(std::move(Q), r, options);
}

std::vector<int> coarse_rows_in_use(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                    double& mask) {
  std::vector<int> rows;
  mask = 0.0;
  for (Eigen::Index k : nonzero_rows(X, Xn)) {
    rows.push_back(static_cast<int>(k));
    mask += std::ldexp(1.0, static_cast<int>(k));
  }
  rows.push_back(static_cast<int>(X.rows()));
  return rows;
}

void append_packed_block(const Eigen::MatrixXd& M, const std::vector<int>& rows, bool symmetric,
                         std::vector<double>& out) {
  const std::size_t m = rows.size();
  for (std::size_t j = 0; j < m; ++j)
    for (std::size_t i = 0; i < (symmetric ? j + 1 : m); ++i) out.push_back(M(rows[i], rows[j]));
}

void add_packed_block(const std::vector<double>& t, std::size_t& at, const std::vector<int>& rows,
                      bool symmetric, Eigen::MatrixXd& M) {
  const std::size_t m = rows.size();
  for (std::size_t j = 0; j < m; ++j)
    for (std::size_t i = 0; i < (symmetric ? j + 1 : m); ++i, ++at) {
      M(rows[i], rows[j]) += t[at];
      if (symmetric && i != j) M(rows[j], rows[i]) += t[at];
    }
}

namespace {

std::runtime_error malformed_terms(int agent, const std::string& why) {
  return std::runtime_error("malformed message: coarse terms of agent " + std::to_string(agent) +
                            ": " + why);
}

}  // namespace

void check_coarse_term_vectors(std::size_t vectors, int blocks) {
  if (vectors != static_cast<std::size_t>(blocks))
    throw std::runtime_error("coarse correction: " + std::to_string(vectors) +
                             " term vectors for " + std::to_string(blocks) + " blocks");
}

void check_coarse_term_size(const std::vector<double>& terms, std::size_t expected, int agent) {
  if (terms.size() != expected)
    throw malformed_terms(
        agent, std::to_string(terms.size()) + " values, expected " + std::to_string(expected));
}

std::vector<int> coarse_term_rows(const std::vector<double>& terms, int r, int agent) {
  auto bad = [&](const std::string& why) { return malformed_terms(agent, why); };
  if (terms.empty()) throw bad("none");
  const double mask = terms[0];
  if (!(mask >= 0 && mask < std::ldexp(1.0, r)) || std::floor(mask) != mask)
    throw bad("row mask " + std::to_string(mask) + " does not fit rank " + std::to_string(r));
  std::vector<int> rows;
  const auto bits = static_cast<unsigned long long>(mask);
  for (int k = 0; k < r; ++k)
    if (bits & (1ull << k)) rows.push_back(k);
  rows.push_back(r);
  return rows;
}

CoarseResult solve_coarse_matrix(CoarseMatrix Q, int r, const CoarseOptions& options) {
  const int N = static_cast<int>(Q.diag.size());
  const int s = r + 1;
  // Rows of the lifted space that some pose uses. An iterate with r - d zero rows (chordal
  // start) keeps them exactly zero: the motions act on the used rows only, so the agents'
  // row-restricted local math stays as cheap as before.
  std::vector<int> act;
  for (int k = 0; k < r; ++k)
    for (int a = 0; a < N; ++a)
      if (Q.diag[static_cast<std::size_t>(a)](k, k) != 0.0) {
        act.push_back(k);
        break;
      }
  const int q = static_cast<int>(act.size());
  // From here on the problem lives on those rows and the homogeneous one: Z_a = [G_a c_a] is
  // q x (q+1) (the full motion is the identity elsewhere).
  {
    std::vector<int> idx = act;
    idx.push_back(r);
    for (auto& D : Q.diag) D = D(idx, idx).eval();
    for (auto& o : Q.off)
      for (auto& [b, M] : o) M = M(idx, idx).eval();
  }
  const int sc = q + 1;
  std::vector<std::pair<int, int>> gens;  // rotation generators e_i e_j^T - e_j e_i^T
  for (int i = 0; i < q; ++i)
    for (int j = i + 1; j < q; ++j) gens.emplace_back(i, j);
  const int m = static_cast<int>(gens.size());
  const int p = m + q;  // unknowns per block

  CoarseResult res;
  std::vector<Mat> Z(static_cast<std::size_t>(N), Mat::Zero(q, sc));
  for (auto& z : Z) z.leftCols(q).setIdentity();
  res.cost_before = coarse_cost(Q, Z);
  double cost = res.cost_before;

  // Directions of block a's unknowns at Z_a: [S G_a, 0] per generator, e_k in the last column.
  auto directions = [&](const Mat& Za) {
    std::vector<Mat> D(static_cast<std::size_t>(p), Mat::Zero(q, sc));
    for (int k = 0; k < m; ++k) {
      const auto [i, j] = gens[static_cast<std::size_t>(k)];
      D[static_cast<std::size_t>(k)].row(i).head(q) = Za.row(j).head(q);
      D[static_cast<std::size_t>(k)].row(j).head(q) = -Za.row(i).head(q);
    }
    for (int k = 0; k < q; ++k) D[static_cast<std::size_t>(m + k)](k, q) = 1.0;
    return D;
  };

  double lambda = 1e-4;
  const Eigen::Index n = static_cast<Eigen::Index>(N) * p;
  while (res.iterations < options.max_iterations && p > 0 && cost > 0) {
    // Gauss-Newton model of the cost in the unknowns: gradient g, Hessian H (Q_c restricted
    // to the directions).
    std::vector<std::vector<Mat>> D(static_cast<std::size_t>(N));
    for (int a = 0; a < N; ++a)
      D[static_cast<std::size_t>(a)] = directions(Z[static_cast<std::size_t>(a)]);
    Eigen::VectorXd g(n);
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::VectorXd hdiag = Eigen::VectorXd::Zero(n);
    for (int a = 0; a < N; ++a) {
      const std::size_t ua = static_cast<std::size_t>(a);
      Mat E = Z[ua] * Q.diag[ua];
      for (const auto& [b, Qab] : Q.off[ua]) E += Z[static_cast<std::size_t>(b)] * Qab.transpose();
      E *= 2.0;
      for (int k = 0; k < p; ++k)
        g(a * p + k) = E.cwiseProduct(D[ua][static_cast<std::size_t>(k)]).sum();
      auto add_block = [&](int b, const Mat& Qab) {
        for (int k = 0; k < p; ++k) {
          const Mat DQ = D[ua][static_cast<std::size_t>(k)] * Qab;
          for (int l = 0; l < p; ++l) {
            const double h =
                2.0 *
                DQ.cwiseProduct(D[static_cast<std::size_t>(b)][static_cast<std::size_t>(l)]).sum();
            if (h != 0.0) trip.emplace_back(a * p + k, b * p + l, h);
            if (a == b && k == l) hdiag(a * p + k) = h;
          }
        }
      };
      add_block(a, Q.diag[ua]);
      for (const auto& [b, Qab] : Q.off[ua]) add_block(b, Qab);
    }
    const double floor = 1e-12 * std::max(1.0, hdiag.maxCoeff());
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(trip.begin(), trip.end());
    bool accepted = false;
    while (!accepted && lambda <= 1e8 && res.iterations < options.max_iterations) {
      ++res.iterations;
      Eigen::SparseMatrix<double> M = H;
      for (Eigen::Index k = 0; k < n; ++k) M.coeffRef(k, k) += lambda * hdiag(k) + floor;
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(M);
      if (ldlt.info() != Eigen::Success) {
        lambda *= 10;
        continue;
      }
      const Eigen::VectorXd x = ldlt.solve(-g);
      std::vector<Mat> Zn = Z;
      const Mat I = Mat::Identity(q, q);
      for (int a = 0; a < N; ++a) {
        const std::size_t ua = static_cast<std::size_t>(a);
        Mat Wa = Mat::Zero(q, q);
        for (int k = 0; k < m; ++k) {
          const auto [i, j] = gens[static_cast<std::size_t>(k)];
          Wa(i, j) += x(a * p + k);
          Wa(j, i) -= x(a * p + k);
        }
        // Cayley transform: orthogonal up to round-off.
        const Mat C = (I - 0.5 * Wa).partialPivLu().solve(I + 0.5 * Wa);
        Zn[ua].leftCols(q) = C * Z[ua].leftCols(q);
        Zn[ua].col(q) += x.segment(a * p + m, q);
      }
      const double cn = coarse_cost(Q, Zn);
      if (std::isfinite(cn) && cn < cost) {
        const double decrease = cost - cn;
        Z = std::move(Zn);
        cost = cn;
        res.moved = true;
        accepted = true;
        lambda = std::max(lambda * 0.1, 1e-12);
        if (decrease < options.rel_tol * cost) lambda = 1e300;  // converged: leave both loops
      } else {
        lambda *= 10;
      }
    }
    if (!accepted || lambda > 1e8) break;
  }
  res.cost_after = cost;
  // The full r x (r+1) motions: the identity outside the used rows.
  res.motions.assign(static_cast<std::size_t>(N), Mat::Zero(r, s));
  for (int a = 0; a < N; ++a) {
    Mat& full = res.motions[static_cast<std::size_t>(a)];
    full.leftCols(r).setIdentity();
    for (int i = 0; i < q; ++i) {
      for (int j = 0; j < q; ++j)
        full(act[static_cast<std::size_t>(i)], act[static_cast<std::size_t>(j)]) =
            Z[static_cast<std::size_t>(a)](i, j);
      full(act[static_cast<std::size_t>(i)], r) = Z[static_cast<std::size_t>(a)](i, q);
    }
  }
  return res;
}

void apply_motion(const Eigen::MatrixXd& Z, int d, Eigen::MatrixXd& X, Eigen::Index first,
                  Eigen::Index count) {
  const Eigen::Index r = X.rows();
  const Eigen::Index w = d + 1;
  const Eigen::Index n = X.cols() / w;
  const Eigen::Index end = count < 0 ? n : std::min(n, first + count);
  const auto G = Z.leftCols(r);
  const auto c = Z.col(r);
  for (Eigen::Index i = first; i < end; ++i) {
    auto Xi = X.middleCols(w * i, w);
    const Eigen::MatrixXd moved = G * Xi;
    Xi = moved;
    Xi.col(d) += c;
  }
}

}  // namespace tessera
