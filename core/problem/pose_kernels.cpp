#include <stdexcept>
#include <tessera/problem/pose_kernels.hpp>

#include "manifold/pose_lanes.hpp"
#include "manifold/sym_product.hpp"

namespace tessera {
namespace {

// R: the row count, or Eigen::Dynamic. The accumulator is a fixed-size Eigen vector so that it
// lives in registers (through a pointer it would chain every update through memory).
template <int R>
void dense_times_sparse(const double* X, Eigen::Index r, const SparseMatrix& Q, double scale,
                        double* out) {
  using Vec = Eigen::Matrix<double, R, 1>;
  using ConstMap = Eigen::Map<const Vec>;
  const auto* outer = Q.outerIndexPtr();
  const auto* nnz = Q.innerNonZeroPtr();  // null when compressed
  const auto* inner = Q.innerIndexPtr();
  const double* value = Q.valuePtr();
  Vec acc(r);
  for (Eigen::Index j = 0; j < Q.outerSize(); ++j) {
    acc.setZero();
    const Eigen::Index begin = outer[j];
    const Eigen::Index end = nnz ? begin + nnz[j] : outer[j + 1];
    for (Eigen::Index p = begin; p < end; ++p)
      acc += value[p] * ConstMap(X + r * static_cast<Eigen::Index>(inner[p]), r);
    Eigen::Map<Vec>(out + r * j, r) = scale * acc;
  }
}

template <int D, int R>
void hessian_projection(const double* X, const double* G, const double* V, Eigen::Index r,
                        Eigen::Index n, double* H) {
  const Eigen::Index rr = R > 0 ? R : r;
  const Eigen::Index stride = rr * (D + 1);
  Eigen::Index i = 0;
  if constexpr (D == 3 && R == 3) {
    // pose_lanes() poses at a time, one a vector lane: the same bits as the loop below.
    const int lanes = pose_lanes();
    for (; i + lanes <= n; i += lanes)
      hessian_projection_in_lanes(X + stride * i, G + stride * i, V + stride * i, lanes,
                                  H + stride * i);
  }
  for (; i < n; ++i) {
    const double* Xi = X + stride * i;
    const double* Vi = V + stride * i;
    double* Hi = H + stride * i;
    double SH[D][D], SG[D][D];
    sym_product<D, R>(Xi, Hi, rr, SH);
    sym_product<D, R>(Xi, G + stride * i, rr, SG);
#pragma GCC unroll 16
    for (int b = 0; b < D; ++b) {
      double* h = Hi + b * rr;
#pragma GCC unroll 16
      for (int a = 0; a < D; ++a) {
        const double wx = SH[a][b], wv = SG[a][b];
        const double* xa = Xi + a * rr;
        const double* va = Vi + a * rr;
#pragma GCC unroll 16
        for (Eigen::Index k = 0; k < rr; ++k) h[k] -= wx * xa[k] + wv * va[k];
      }
    }
  }
}

template <int D>
void hessian_projection_dispatch(const double* X, const double* G, const double* V, Eigen::Index r,
                                 Eigen::Index n, double* H) {
  switch (r) {
    case 2:
      return hessian_projection<D, 2>(X, G, V, r, n, H);
    case 3:
      return hessian_projection<D, 3>(X, G, V, r, n, H);
    case 4:
      return hessian_projection<D, 4>(X, G, V, r, n, H);
    case 5:
      return hessian_projection<D, 5>(X, G, V, r, n, H);
    case 6:
      return hessian_projection<D, 6>(X, G, V, r, n, H);
    default:
      return hessian_projection<D, 0>(X, G, V, r, n, H);
  }
}

}  // namespace

void scaled_dense_times_sparse(const Eigen::MatrixXd& X, const SparseMatrix& Q, double scale,
                               Eigen::MatrixXd& out) {
  if (X.cols() != Q.rows())
    throw std::invalid_argument("scaled_dense_times_sparse: inner dimensions differ");
  const Eigen::Index r = X.rows();
  out.resize(r, Q.cols());
  switch (r) {
    case 1:  // the certificate's vectors (one row): the dynamic kernel zeroed a heap row a column
      return dense_times_sparse<1>(X.data(), r, Q, scale, out.data());
    case 2:
      return dense_times_sparse<2>(X.data(), r, Q, scale, out.data());
    case 3:
      return dense_times_sparse<3>(X.data(), r, Q, scale, out.data());
    case 4:
      return dense_times_sparse<4>(X.data(), r, Q, scale, out.data());
    case 5:
      return dense_times_sparse<5>(X.data(), r, Q, scale, out.data());
    case 6:
      return dense_times_sparse<6>(X.data(), r, Q, scale, out.data());
    default:
      return dense_times_sparse<Eigen::Dynamic>(X.data(), r, Q, scale, out.data());
  }
}

void apply_hessian_projection(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G,
                              const Eigen::MatrixXd& V, int d, Eigen::MatrixXd& H) {
  if (d != 2 && d != 3) throw std::invalid_argument("apply_hessian_projection: d must be 2 or 3");
  const Eigen::Index r = X.rows(), cols = X.cols();
  if (G.rows() != r || V.rows() != r || H.rows() != r || G.cols() != cols || V.cols() != cols ||
      H.cols() != cols || cols % (d + 1) != 0)
    throw std::invalid_argument("apply_hessian_projection: operands of different shapes");
  const Eigen::Index n = cols / (d + 1);
  if (d == 2)
    hessian_projection_dispatch<2>(X.data(), G.data(), V.data(), r, n, H.data());
  else
    hessian_projection_dispatch<3>(X.data(), G.data(), V.data(), r, n, H.data());
}

}  // namespace tessera
