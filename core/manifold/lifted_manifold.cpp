#include <Eigen/SVD>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/manifold/lifted_manifold.hpp>
#include <utility>

#include "manifold/pose_lanes.hpp"
#include "manifold/sym_product.hpp"

namespace tessera {
namespace {
// d x d scratch matrices live on the stack (d <= 3): no heap traffic in per-pose loops.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
}  // namespace

LiftedManifold::LiftedManifold(int r, int d, std::size_t n) : r_(r), d_(d), n_(n) {
  if (d < 2 || d > 3) throw std::invalid_argument("LiftedManifold: d must be 2 or 3");
  if (r < d) throw std::invalid_argument("LiftedManifold: rank r must be >= d");
}

Eigen::MatrixXd polar_factor(const Eigen::MatrixXd& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  return svd.matrixU() * svd.matrixV().transpose();
}

Eigen::MatrixXd LiftedManifold::project(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd out = X;
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    out.middleCols(c, d_) = polar_factor(X.middleCols(c, d_));
  }
  return out;
}

namespace {

// sym(A_i^T B_i) for the d x d Stiefel block of pose i, on raw column-major data: with
// dynamic sizes Eigen evaluates these tiny products coefficient by coefficient, and they were
// the top entry of the solver's profile (38% on kitti_05).
void block_sym_product(const double* A, const double* B, Eigen::Index r, int d, double* sym) {
  double S[9];
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      double acc = 0.0;
      const double* Aa = A + a * r;
      const double* Bb = B + b * r;
      for (Eigen::Index k = 0; k < r; ++k) acc += Aa[k] * Bb[k];
      S[a * d + b] = acc;
    }
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) sym[a * d + b] = 0.5 * (S[a * d + b] + S[b * d + a]);
}

// out_i (r x d) += sign * C_i * sym, C_i the d columns of pose i in C.
void block_multiply_add(const double* C, const double* sym, Eigen::Index r, int d, double sign,
                        double* out) {
  for (int b = 0; b < d; ++b) {
    double* o = out + b * r;
    for (int a = 0; a < d; ++a) {
      const double w = sign * sym[a * d + b];
      const double* Ca = C + a * r;
      for (Eigen::Index k = 0; k < r; ++k) o[k] += w * Ca[k];
    }
  }
}

}  // namespace

namespace {

// tangent_project's loop for a fixed d and (R > 0) a fixed number of rows: the operations of
// block_sym_product and block_multiply_add in the same order (bit-identical), unrolled
// (sym_product.hpp says why). The agents' updates run at r = d (their active rows), where this
// is most of a tCG iteration's projections.
template <int D, int R>
void tangent_project_poses(const double* X, const double* V, Eigen::Index r_runtime, std::size_t n,
                           double* out) {
  const Eigen::Index r = R > 0 ? R : r_runtime;
  std::size_t i = 0;
  if constexpr (D == 3 && R == 3) {
    // pose_lanes() poses at a time, one a vector lane: the same bits as the loop below.
    const std::size_t lanes = static_cast<std::size_t>(pose_lanes());
    for (; i + lanes <= n; i += lanes) {
      const Eigen::Index offset = 12 * static_cast<Eigen::Index>(i);
      tangent_project_in_lanes(X + offset, V + offset, static_cast<int>(lanes), out + offset);
      if (out != V)  // the translation columns are V's
        for (std::size_t l = 0; l < lanes; ++l)
          for (Eigen::Index k = 9; k < 12; ++k) out[offset + 12 * l + k] = V[offset + 12 * l + k];
    }
  }
  for (; i < n; ++i) {
    const Eigen::Index offset = r * static_cast<Eigen::Index>((D + 1) * i);
    const double* A = X + offset;
    const double* B = V + offset;
    double sym[D][D];
    sym_product<D, R>(A, B, r, sym);
    double* o0 = out + offset;
#pragma GCC unroll 16
    for (int b = 0; b < D; ++b) {
      double* o = o0 + b * r;
      const double* v = B + b * r;  // o itself when out is V
#pragma GCC unroll 16
      for (int a = 0; a < D; ++a) {
        const double w = -1.0 * sym[a][b];
        const double* Ca = A + a * r;
#pragma GCC unroll 16
        for (Eigen::Index k = 0; k < r; ++k) o[k] = (a == 0 ? v[k] : o[k]) + w * Ca[k];
      }
    }
    if (out != V)  // the translation column is V's
      for (Eigen::Index k = 0; k < r; ++k) o0[D * r + k] = B[D * r + k];
  }
}

// tangent_project_poses for dimension d and X's rows: V's n poses into out (out may be V).
void tangent_project_all(int d, const Eigen::MatrixXd& X, const double* V, std::size_t n,
                         double* out) {
  const Eigen::Index r = X.rows();
  if (d == 2) {
    if (r == 2)
      tangent_project_poses<2, 2>(X.data(), V, r, n, out);
    else
      tangent_project_poses<2, 0>(X.data(), V, r, n, out);
  } else {
    if (r == 3)
      tangent_project_poses<3, 3>(X.data(), V, r, n, out);
    else
      tangent_project_poses<3, 0>(X.data(), V, r, n, out);
  }
}

}  // namespace

Eigen::MatrixXd LiftedManifold::tangent_project(const Eigen::MatrixXd& X,
                                                const Eigen::MatrixXd& V) const {
  if (V.cols() != (d_ + 1) * static_cast<Eigen::Index>(n_) || V.rows() != X.rows())
    return tangent_project(X, Eigen::MatrixXd(V));
  // Written from V straight into a new matrix (no copy of V first): the same sums.
  Eigen::MatrixXd out(V.rows(), V.cols());
  tangent_project_all(d_, X, V.data(), n_, out.data());
  return out;
}

Eigen::MatrixXd LiftedManifold::tangent_project(const Eigen::MatrixXd& X,
                                                Eigen::MatrixXd&& V) const {
  // Pose by pose, sym(Y_i^T V_i) is read before V_i is updated, so V may be the output.
  Eigen::MatrixXd out = std::move(V);
  tangent_project_all(d_, X, out.data(), n_, out.data());
  return out;
}

Eigen::MatrixXd LiftedManifold::retract(const Eigen::MatrixXd& X, const Eigen::MatrixXd& V) const {
  return project(X + V);
}

Eigen::MatrixXd LiftedManifold::weingarten_term(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G,
                                                const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  const Eigen::Index r = X.rows();
  double sym[9];
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index offset = r * static_cast<Eigen::Index>((d_ + 1) * i);
    block_sym_product(X.data() + offset, G.data() + offset, r, d_, sym);
    block_multiply_add(V.data() + offset, sym, r, d_, 1.0, out.data() + offset);
  }
  return out;
}

double LiftedManifold::distance_from_manifold(const Eigen::MatrixXd& X) const {
  double worst = 0.0;
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    SmallMatrix S = X.middleCols(c, d_).transpose() * X.middleCols(c, d_);
    worst = std::max(worst, (S - SmallMatrix::Identity(d_, d_)).norm());
  }
  return worst;
}

}  // namespace tessera
