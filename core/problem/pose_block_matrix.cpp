#include <algorithm>
#include <stdexcept>
#include <tessera/problem/pose_block_matrix.hpp>

#include "util/avx_kernels.hpp"
#include "util/double_pair.hpp"

namespace tessera {

PoseBlockMatrix::PoseBlockMatrix(const SparseMatrix& Q, int w) : w_(w), rows_(Q.rows()) {
  if (w < 1 || Q.rows() % w != 0 || Q.cols() % w != 0)
    throw std::invalid_argument("PoseBlockMatrix: dimensions are not multiples of the block size");
  const Eigen::Index block_cols = Q.cols() / w;
  start_.assign(static_cast<std::size_t>(block_cols) + 1, 0);
  std::vector<int> rows;
  for (Eigen::Index J = 0; J < block_cols; ++J) {
    // The block rows any of the w columns touches, in increasing order.
    rows.clear();
    for (Eigen::Index c = w * J; c < w * (J + 1); ++c)
      for (SparseMatrix::InnerIterator it(Q, c); it; ++it)
        rows.push_back(static_cast<int>(it.row() / w));
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    const std::size_t first = row_block_.size();
    row_block_.insert(row_block_.end(), rows.begin(), rows.end());
    values_.resize(row_block_.size() * static_cast<std::size_t>(w * w), 0.0);
    for (Eigen::Index c = w * J; c < w * (J + 1); ++c) {
      const auto q = static_cast<std::size_t>(c - w * J);
      for (SparseMatrix::InnerIterator it(Q, c); it; ++it) {
        const int I = static_cast<int>(it.row() / w);
        const auto b = first + static_cast<std::size_t>(
                                   std::lower_bound(rows.begin(), rows.end(), I) - rows.begin());
        values_[b * static_cast<std::size_t>(w * w) +
                static_cast<std::size_t>(it.row() % w) * static_cast<std::size_t>(w) + q] =
            it.value();
      }
    }
    start_[static_cast<std::size_t>(J) + 1] = row_block_.size();
  }
}

std::size_t PoseBlockMatrix::bytes() const {
  return values_.size() * sizeof(double) + row_block_.size() * sizeof(int) +
         start_.size() * sizeof(std::size_t);
}

namespace {

// R: X's row count, or Eigen::Dynamic; W: the block size. Each output column's accumulator
// receives its terms block by block in increasing block row and, within a block, in increasing
// row: the order of the CSC column's non-zeros (scaled_dense_times_sparse).
template <int W, int R>
void block_times(const double* X, Eigen::Index r, const std::vector<std::size_t>& start,
                 const std::vector<int>& row_block, const std::vector<double>& values, double scale,
                 double* out) {
  using Vec = Eigen::Matrix<double, R, 1>;
  using ConstMap = Eigen::Map<const Vec>;
  const Eigen::Index pose = r * W;
  Vec acc[W];
  for (std::size_t J = 0; J + 1 < start.size(); ++J) {
    for (int q = 0; q < W; ++q) acc[q].setZero(r);
    for (std::size_t b = start[J]; b < start[J + 1]; ++b) {
      const double* x = X + pose * row_block[b];
      const double* v = values.data() + b * W * W;
#pragma GCC unroll 4
      for (int q = 0; q < W; ++q)
#pragma GCC unroll 4
        for (int p = 0; p < W; ++p) acc[q] += v[p * W + q] * ConstMap(x + r * p, r);
    }
    double* o = out + pose * static_cast<Eigen::Index>(J);
    for (int q = 0; q < W; ++q) Eigen::Map<Vec>(o + r * q, r) = scale * acc[q];
  }
}

// block_times<W, 3> with rows 0 and 1 in one SSE2 register and row 2 apart: Eigen does not
// vectorise a 3-vector, and r = 3 is the 3D agents' active rows, where most of the products run.
// Lane by lane the same multiplications and additions, so the same values.
template <int W>
void block_times_3(const double* X, const std::vector<std::size_t>& start,
                   const std::vector<int>& row_block, const std::vector<double>& values,
                   double scale, double* out) {
  constexpr Eigen::Index pose = 3 * W;
  for (std::size_t J = 0; J + 1 < start.size(); ++J) {
    DoublePair a01[W];
    double a2[W];
    for (int q = 0; q < W; ++q) {
      a01[q] = DoublePair{0.0, 0.0};
      a2[q] = 0.0;
    }
    for (std::size_t b = start[J]; b < start[J + 1]; ++b) {
      const double* x = X + pose * row_block[b];
      const double* v = values.data() + b * W * W;
      DoublePair x01[W];
      for (int p = 0; p < W; ++p) x01[p] = load_pair(x + 3 * p);
#pragma GCC unroll 4
      for (int q = 0; q < W; ++q)
#pragma GCC unroll 4
        for (int p = 0; p < W; ++p) {
          const double c = v[p * W + q];
          a01[q] += c * x01[p];
          a2[q] += c * x[3 * p + 2];
        }
    }
    double* o = out + pose * static_cast<Eigen::Index>(J);
    for (int q = 0; q < W; ++q) {
      const DoublePair s = scale * a01[q];
      o[3 * q] = s[0];
      o[3 * q + 1] = s[1];
      o[3 * q + 2] = scale * a2[q];
    }
  }
}

// block_times<4, 3> for the 3D agents' rank-3 products (most of them): the 3 x 4 accumulators
// of a block column are six registers of two output columns each. A block's row p (its entries
// (p, 0..3), adjacent in the row-major block) is two registers, each multiplied by X's entry
// (a, p) in both lanes: only full-width operations, against block_times_3's half-empty row 2
// and one broadcast per entry. Each accumulator still takes its terms in increasing block row,
// then in increasing p, so the values are the same.
inline void block_times_3_by_4(const double* X, const std::vector<std::size_t>& start,
                               const std::vector<int>& row_block, const std::vector<double>& values,
                               double scale, double* out) {
  constexpr Eigen::Index pose = 12;
  for (std::size_t J = 0; J + 1 < start.size(); ++J) {
    DoublePair acc[3][2];
    for (int a = 0; a < 3; ++a) acc[a][0] = acc[a][1] = DoublePair{0.0, 0.0};
    for (std::size_t b = start[J]; b < start[J + 1]; ++b) {
      const double* x = X + pose * row_block[b];
      const double* v = values.data() + b * 16;
#pragma GCC unroll 4
      for (int p = 0; p < 4; ++p) {
        const DoublePair v01 = load_pair(v + 4 * p), v23 = load_pair(v + 4 * p + 2);
#pragma GCC unroll 3
        for (int a = 0; a < 3; ++a) {
          const DoublePair xa = {x[3 * p + a], x[3 * p + a]};
          acc[a][0] += xa * v01;
          acc[a][1] += xa * v23;
        }
      }
    }
    double* o = out + pose * static_cast<Eigen::Index>(J);
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) {
      const DoublePair s01 = scale * acc[a][0], s23 = scale * acc[a][1];
      o[a] = s01[0];
      o[3 + a] = s01[1];
      o[6 + a] = s23[0];
      o[9 + a] = s23[1];
    }
  }
}

#ifdef TESSERA_AVX_KERNELS
// block_times_3_by_4 with a block row's four entries in one AVX register: the accumulator of
// output row a holds its four columns, and each term is X's entry (a, p) broadcast times the
// block's row p. The same multiplications and additions per entry in the same order (no FMA),
// so the same values, for half the vector instructions.
__attribute__((target("avx"))) void block_times_3_by_4_avx(const double* X,
                                                           const std::vector<std::size_t>& start,
                                                           const std::vector<int>& row_block,
                                                           const std::vector<double>& values,
                                                           double scale, double* out) {
  constexpr Eigen::Index pose = 12;
  const __m256d s = _mm256_set1_pd(scale);
  for (std::size_t J = 0; J + 1 < start.size(); ++J) {
    __m256d acc0 = _mm256_setzero_pd(), acc1 = acc0, acc2 = acc0;
    for (std::size_t b = start[J]; b < start[J + 1]; ++b) {
      const double* x = X + pose * row_block[b];
      const double* v = values.data() + b * 16;
#pragma GCC unroll 4
      for (int p = 0; p < 4; ++p) {
        const __m256d row = _mm256_loadu_pd(v + 4 * p);
        acc0 = _mm256_add_pd(acc0, _mm256_mul_pd(_mm256_broadcast_sd(x + 3 * p), row));
        acc1 = _mm256_add_pd(acc1, _mm256_mul_pd(_mm256_broadcast_sd(x + 3 * p + 1), row));
        acc2 = _mm256_add_pd(acc2, _mm256_mul_pd(_mm256_broadcast_sd(x + 3 * p + 2), row));
      }
    }
    alignas(32) double r[3][4];
    _mm256_store_pd(r[0], _mm256_mul_pd(s, acc0));
    _mm256_store_pd(r[1], _mm256_mul_pd(s, acc1));
    _mm256_store_pd(r[2], _mm256_mul_pd(s, acc2));
    double* o = out + pose * static_cast<Eigen::Index>(J);
#pragma GCC unroll 4
    for (int q = 0; q < 4; ++q) {
      o[3 * q] = r[0][q];
      o[3 * q + 1] = r[1][q];
      o[3 * q + 2] = r[2][q];
    }
  }
}
#endif

template <int W>
void block_times_rows(const double* X, Eigen::Index r, const std::vector<std::size_t>& start,
                      const std::vector<int>& row_block, const std::vector<double>& values,
                      double scale, double* out) {
  switch (r) {
    case 1:  // the certificate's LOBPCG vectors: the dynamic kernel spent ~4x the instructions
      return block_times<W, 1>(X, r, start, row_block, values, scale, out);
    case 2:
      return block_times<W, 2>(X, r, start, row_block, values, scale, out);
    case 3:
      if constexpr (W == 4) {
#ifdef TESSERA_AVX_KERNELS
        if (avx_kernels_enabled())
          return block_times_3_by_4_avx(X, start, row_block, values, scale, out);
#endif
        return block_times_3_by_4(X, start, row_block, values, scale, out);
      } else
        return block_times_3<W>(X, start, row_block, values, scale, out);
    case 4:
      return block_times<W, 4>(X, r, start, row_block, values, scale, out);
    case 5:
      return block_times<W, 5>(X, r, start, row_block, values, scale, out);
    default:
      return block_times<W, Eigen::Dynamic>(X, r, start, row_block, values, scale, out);
  }
}

}  // namespace

void PoseBlockMatrix::times(const Eigen::MatrixXd& X, double scale, Eigen::MatrixXd& out) const {
  if (X.cols() != rows_)
    throw std::invalid_argument("PoseBlockMatrix::times: inner dimensions differ");
  const Eigen::Index r = X.rows();
  out.resize(r, cols());
  if (w_ == 3)
    return block_times_rows<3>(X.data(), r, start_, row_block_, values_, scale, out.data());
  if (w_ == 4)
    return block_times_rows<4>(X.data(), r, start_, row_block_, values_, scale, out.data());
  throw std::invalid_argument("PoseBlockMatrix::times: block size must be 3 or 4 (d = 2 or 3)");
}

}  // namespace tessera
