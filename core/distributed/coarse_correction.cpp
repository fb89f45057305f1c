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

namespace tessera {

void CoarseOptions::validate() const {
  if (every < 1) throw InputError("CoarseOptions.every must be >= 1");
  if (max_iterations < 1) throw InputError("CoarseOptions.max_iterations must be >= 1");
  if (!(rel_tol >= 0 && rel_tol < 1)) throw InputError("CoarseOptions.rel_tol must be in [0, 1)");
}

CoarseTerms::CoarseTerms(int id, int d, const BlockLayout& layout,
                         const std::vector<std::size_t>& owned,
                         const std::vector<std::size_t>& neighbours,
                         const std::vector<Measurement>& measurements)
    : d_(d), degree_(layout.adjacent[static_cast<std::size_t>(id)].size()) {
  std::unordered_map<std::size_t, std::size_t> own_slot, neighbour_slot;
  for (std::size_t k = 0; k < owned.size(); ++k) own_slot[owned[k]] = k;
  for (std::size_t k = 0; k < neighbours.size(); ++k) neighbour_slot[neighbours[k]] = k;
  for (const Measurement& m : measurements) {
    // Counted by the owner of the source pose only, so each cut edge enters Q_c once.
    const auto i = own_slot.find(m.i);
    const auto j = neighbour_slot.find(m.j);
    if (i == own_slot.end() || j == neighbour_slot.end()) continue;
    const int b = layout.owner[m.j];
    const int k = layout.adjacency_index(id, b);
    if (k < 0) throw std::logic_error("CoarseTerms: cut edge to a block that is not adjacent");
    edges_.push_back(Edge{i->second, j->second, k, m.R, m.t, m.kappa, m.tau});
  }
}

std::size_t CoarseTerms::size(int r) const {
  const std::size_t s = static_cast<std::size_t>(r) + 1;
  return 3 * s * s * degree_;
}

std::vector<double> CoarseTerms::compute(const Eigen::MatrixXd& X,
                                         const Eigen::MatrixXd& Xn) const {
  const int r = static_cast<int>(X.rows());
  const int s = r + 1;
  const int w = d_ + 1;
  std::vector<double> out(size(r), 0.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(s, w), B = Eigen::MatrixXd::Zero(s, w);
  for (const Edge& e : edges_) {
    const auto Xi = X.middleCols(static_cast<Eigen::Index>(w * e.own_slot), w);
    const auto Xj = Xn.middleCols(static_cast<Eigen::Index>(w * e.neighbour_slot), w);
    const double sk = std::sqrt(e.kappa), st = std::sqrt(e.tau);
    A.topLeftCorner(r, d_) = sk * Xj.leftCols(d_);
    A.col(d_).head(r) = st * Xj.col(d_);
    A(r, d_) = st;
    B.topLeftCorner(r, d_) = sk * (Xi.leftCols(d_) * e.R);
    B.col(d_).head(r) = st * (Xi.col(d_) + Xi.leftCols(d_) * e.t);
    B(r, d_) = st;
    double* base = out.data() + 3 * s * s * e.adjacency;
    Eigen::Map<Eigen::MatrixXd> Daa(base, s, s), Dbb(base + s * s, s, s),
        Dab(base + 2 * s * s, s, s);
    Daa.noalias() += B * B.transpose();
    Dbb.noalias() += A * A.transpose();
    Dab.noalias() -= B * A.transpose();
  }
  return out;
}

namespace {

using Mat = Eigen::MatrixXd;

// Q_c in blocks: diag[a] = Q_aa, off[a][b] = Q_ab for every adjacent b (both directions kept).
struct CoarseMatrix {
  std::vector<Mat> diag;
  std::vector<std::map<int, Mat>> off;
};

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
  const std::size_t ss = static_cast<std::size_t>(s * s);
  if (terms.size() != static_cast<std::size_t>(N))
    throw std::runtime_error("coarse correction: " + std::to_string(terms.size()) +
                             " term vectors for " + std::to_string(N) + " blocks");
  CoarseMatrix Q;
  Q.diag.assign(static_cast<std::size_t>(N), Mat::Zero(s, s));
  Q.off.resize(static_cast<std::size_t>(N));
  for (int a = 0; a < N; ++a) {
    const auto& adj = layout.adjacent[static_cast<std::size_t>(a)];
    for (int b : adj) {
      Q.off[static_cast<std::size_t>(a)][b] = Mat::Zero(s, s);
      Q.off[static_cast<std::size_t>(b)][a] = Mat::Zero(s, s);
    }
  }
  for (int a = 0; a < N; ++a) {
    const auto& adj = layout.adjacent[static_cast<std::size_t>(a)];
    const std::vector<double>& t = *terms[static_cast<std::size_t>(a)];
    if (t.size() != 3 * ss * adj.size())
      throw std::runtime_error("malformed message: coarse terms of agent " + std::to_string(a) +
                               " have " + std::to_string(t.size()) + " values, expected " +
                               std::to_string(3 * ss * adj.size()));
    for (std::size_t k = 0; k < adj.size(); ++k) {
      const int b = adj[k];
      const double* base = t.data() + 3 * ss * k;
      Eigen::Map<const Mat> Daa(base, s, s), Dbb(base + ss, s, s), Dab(base + 2 * ss, s, s);
      Q.diag[static_cast<std::size_t>(a)] += Daa;
      Q.diag[static_cast<std::size_t>(b)] += Dbb;
      Q.off[static_cast<std::size_t>(a)][b] += Dab;
      Q.off[static_cast<std::size_t>(b)][a] += Dab.transpose();
    }
  }

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
  std::vector<std::pair<int, int>> gens;  // rotation generators e_i e_j^T - e_j e_i^T
  for (int i = 0; i < q; ++i)
    for (int j = i + 1; j < q; ++j) gens.emplace_back(act[i], act[j]);
  const int m = static_cast<int>(gens.size());
  const int p = m + q;  // unknowns per block

  CoarseResult res;
  std::vector<Mat> Z(static_cast<std::size_t>(N), Mat::Zero(r, s));
  for (auto& z : Z) z.leftCols(r).setIdentity();
  res.cost_before = coarse_cost(Q, Z);
  double cost = res.cost_before;

  // Directions of block a's unknowns at Z_a: [S G_a, 0] per generator, e_k in column r.
  auto directions = [&](const Mat& Za) {
    std::vector<Mat> D(static_cast<std::size_t>(p), Mat::Zero(r, s));
    for (int k = 0; k < m; ++k) {
      const auto [i, j] = gens[static_cast<std::size_t>(k)];
      D[static_cast<std::size_t>(k)].row(i).head(r) = Za.row(j).head(r);
      D[static_cast<std::size_t>(k)].row(j).head(r) = -Za.row(i).head(r);
    }
    for (int k = 0; k < q; ++k)
      D[static_cast<std::size_t>(m + k)](act[static_cast<std::size_t>(k)], r) = 1.0;
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
      for (int a = 0; a < N; ++a) {
        const std::size_t ua = static_cast<std::size_t>(a);
        Mat W = Mat::Zero(q, q);
        for (int k = 0; k < m; ++k) {
          const auto [i, j] = gens[static_cast<std::size_t>(k)];
          const auto ii = std::find(act.begin(), act.end(), i) - act.begin();
          const auto jj = std::find(act.begin(), act.end(), j) - act.begin();
          W(ii, jj) += x(a * p + k);
          W(jj, ii) -= x(a * p + k);
        }
        // Cayley transform: exactly orthogonal up to round-off, and the identity on unused rows.
        const Mat I = Mat::Identity(q, q);
        const Mat C = (I - 0.5 * W).partialPivLu().solve(I + 0.5 * W);
        Mat rows(q, r);
        for (int k = 0; k < q; ++k)
          rows.row(k) = Z[ua].row(act[static_cast<std::size_t>(k)]).head(r);
        rows = C * rows;
        for (int k = 0; k < q; ++k) {
          Zn[ua].row(act[static_cast<std::size_t>(k)]).head(r) = rows.row(k);
          Zn[ua](act[static_cast<std::size_t>(k)], r) += x(a * p + m + k);
        }
      }
      const double cn = coarse_cost(Q, Zn);
      if (std::isfinite(cn) && cn < cost) {
        const double decrease = cost - cn;
        Z = std::move(Zn);
        cost = cn;
        res.moved = true;
        accepted = true;
        lambda = std::max(lambda * 0.1, 1e-12);
        if (decrease < options.rel_tol * cost) {
          res.cost_after = cost;
          res.motions = std::move(Z);
          return res;
        }
      } else {
        lambda *= 10;
      }
    }
    if (!accepted) break;
  }
  res.cost_after = cost;
  res.motions = std::move(Z);
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
