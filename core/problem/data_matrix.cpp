#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <tessera/problem/data_matrix.hpp>

namespace tessera {

namespace {

// Q assembled pose pair by pose pair: it is made of (d+1) x (d+1) blocks, one on the diagonal
// per pose and one per ordered pair of poses joined by a measurement. Each block is summed
// densely, measurement after measurement and within a measurement in the order of the formula
// in add_measurement(), which is the order in which a triplet list (duplicates summed in list
// order, as Eigen's setFromTriplets does) would sum it: same values to the last bit. A mask
// records which entries some measurement touched, so the pattern, explicit zeros included, is
// the triplet list's too (the fill-reducing ordering of the preconditioner sees the same
// matrix). Linear in the measurements: no sort of 2d^2 + 4d + 6 triplets per measurement.
class BlockAssembly {
 public:
  BlockAssembly(const std::vector<std::size_t>& slot_of_i,
                const std::vector<std::size_t>& slot_of_j, int d, std::size_t num_cols)
      : w_(d + 1), num_cols_(num_cols) {
    if (w_ * w_ > 32) throw std::invalid_argument("build_data_matrix: d must be at most 4");
    // Row slots of every column slot's blocks: its own slot and the other endpoint of each
    // measurement touching it (counted, placed, then sorted and de-duplicated per column).
    std::vector<std::size_t> fill(num_cols + 1, 0);
    auto count = [&](std::size_t col) {
      if (col < num_cols) fill[col + 1] += 2;
    };
    for (std::size_t k = 0; k < slot_of_i.size(); ++k) {
      count(slot_of_i[k]);
      count(slot_of_j[k]);
    }
    for (std::size_t c = 0; c < num_cols; ++c) fill[c + 1] += fill[c];
    std::vector<std::size_t> rows(fill[num_cols]);
    std::vector<std::size_t> next(fill.begin(), fill.end() - 1);
    auto place = [&](std::size_t col, std::size_t row) {
      if (col < num_cols) rows[next[col]++] = row;
    };
    for (std::size_t k = 0; k < slot_of_i.size(); ++k) {
      const std::size_t i = slot_of_i[k], j = slot_of_j[k];
      place(i, i);
      place(i, j);
      place(j, j);
      place(j, i);
    }
    start_.assign(num_cols + 1, 0);
    row_slot_.reserve(rows.size() / 2 + num_cols);
    for (std::size_t c = 0; c < num_cols; ++c) {
      auto first = rows.begin() + static_cast<std::ptrdiff_t>(fill[c]);
      auto last = rows.begin() + static_cast<std::ptrdiff_t>(fill[c + 1]);
      std::sort(first, last);
      row_slot_.insert(row_slot_.end(), first, std::unique(first, last));
      start_[c + 1] = row_slot_.size();
    }
    values_.assign(row_slot_.size() * static_cast<std::size_t>(w_ * w_), 0.0);
    mask_.assign(row_slot_.size(), 0);
  }

  void add_measurement(const Measurement& m, std::size_t si, std::size_t sj) {
    const int d = w_ - 1;
    const std::size_t ii = find(si, si), jj = find(sj, sj);
    const std::size_t ij = find(sj, si);  // rows of pose i, columns of pose j
    const std::size_t ji = find(si, sj);  // rows of pose j, columns of pose i
    // Rotation term: kappa ||X A||^2 with A = [-R_ij at i; I at j].
    for (int a = 0; a < d; ++a) {
      add(ii, a, a, m.kappa);
      add(jj, a, a, m.kappa);
      for (int b = 0; b < d; ++b) {
        add(ij, a, b, -m.kappa * m.R(a, b));
        add(ji, b, a, -m.kappa * m.R(a, b));
      }
    }
    // Translation term: tau ||X a||^2 with a = [-t_ij at i rotation; -1 at i; +1 at j].
    for (int a = 0; a < d; ++a) {
      for (int b = 0; b < d; ++b) add(ii, a, b, m.tau * m.t(a) * m.t(b));
      add(ii, a, d, m.tau * m.t(a));
      add(ii, d, a, m.tau * m.t(a));
      add(ij, a, d, -m.tau * m.t(a));
      add(ji, d, a, -m.tau * m.t(a));
    }
    add(ii, d, d, m.tau);
    add(jj, d, d, m.tau);
    add(ij, d, d, -m.tau);
    add(ji, d, d, -m.tau);
  }

  // The entries in rows of slots < split (`top`) and >= split (`bottom`, rows shifted up).
  DataMatrixBlocks emit(std::size_t split, std::size_t num_slots) const {
    using Index = Eigen::Index;
    const Index w = w_;
    DataMatrixBlocks out;
    out.own.resize(w * static_cast<Index>(split), w * static_cast<Index>(num_cols_));
    out.neighbour.resize(w * static_cast<Index>(num_slots - split),
                         w * static_cast<Index>(num_cols_));
    std::size_t nnz_top = 0, nnz_bottom = 0;
    for (std::size_t b = 0; b < row_slot_.size(); ++b) {
      const auto n = static_cast<std::size_t>(__builtin_popcount(mask_[b]));
      (row_slot_[b] < split ? nnz_top : nnz_bottom) += n;
    }
    out.own.resizeNonZeros(static_cast<Index>(nnz_top));
    out.neighbour.resizeNonZeros(static_cast<Index>(nnz_bottom));
    SparseMatrix* parts[2] = {&out.own, &out.neighbour};
    std::size_t at[2] = {0, 0};
    for (std::size_t c = 0; c < num_cols_; ++c)
      for (int q = 0; q < w_; ++q) {
        const Index col = w * static_cast<Index>(c) + q;
        for (int s = 0; s < 2; ++s) parts[s]->outerIndexPtr()[col] = static_cast<int>(at[s]);
        for (std::size_t b = start_[c]; b < start_[c + 1]; ++b) {
          const int s = row_slot_[b] < split ? 0 : 1;
          const std::size_t base = s == 0 ? 0 : split;
          for (int p = 0; p < w_; ++p) {
            if (!(mask_[b] >> (p * w_ + q) & 1u)) continue;
            parts[s]->innerIndexPtr()[at[s]] =
                static_cast<int>(w * static_cast<Index>(row_slot_[b] - base) + p);
            parts[s]->valuePtr()[at[s]] = values_[b * static_cast<std::size_t>(w_ * w_) +
                                                  static_cast<std::size_t>(p * w_ + q)];
            ++at[s];
          }
        }
      }
    for (int s = 0; s < 2; ++s)
      parts[s]->outerIndexPtr()[w * static_cast<Index>(num_cols_)] = static_cast<int>(at[s]);
    return out;
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  // Index of the block in column slot `col`, row slot `row`; kNone for an unbuilt column.
  std::size_t find(std::size_t col, std::size_t row) const {
    if (col >= num_cols_) return kNone;
    auto first = row_slot_.begin() + static_cast<std::ptrdiff_t>(start_[col]);
    auto last = row_slot_.begin() + static_cast<std::ptrdiff_t>(start_[col + 1]);
    return static_cast<std::size_t>(std::lower_bound(first, last, row) - row_slot_.begin());
  }

  void add(std::size_t block, int p, int q, double v) {
    if (block == kNone) return;
    const int bit = p * w_ + q;
    double& x = values_[block * static_cast<std::size_t>(w_ * w_) + static_cast<std::size_t>(bit)];
    if (mask_[block] >> bit & 1u) {
      x += v;
    } else {  // the first value is stored, not added to 0 (keeps the sign of a zero)
      x = v;
      mask_[block] |= 1u << bit;
    }
  }

  int w_;
  std::size_t num_cols_;
  std::vector<std::size_t> start_;     // column slot c's blocks: start_[c] .. start_[c+1]-1
  std::vector<std::size_t> row_slot_;  // row slot of every block, ascending per column
  std::vector<double> values_;         // w x w per block, row-major
  std::vector<std::uint32_t> mask_;    // entries touched, bit p * w + q
};

}  // namespace

DataMatrixBlocks build_data_matrix_blocks(const std::vector<const Measurement*>& measurements,
                                          const std::vector<std::size_t>& slot_of_i,
                                          const std::vector<std::size_t>& slot_of_j, int d,
                                          std::size_t num_slots, std::size_t num_owned) {
  if (slot_of_i.size() != measurements.size() || slot_of_j.size() != measurements.size())
    throw std::invalid_argument("build_data_matrix: one slot pair per measurement expected");
  if (num_owned > num_slots)
    throw std::invalid_argument("build_data_matrix: more owned slots than slots");
  for (std::size_t k = 0; k < measurements.size(); ++k)
    if (slot_of_i[k] >= num_slots || slot_of_j[k] >= num_slots)
      throw std::invalid_argument("build_data_matrix: slot out of range");
  BlockAssembly assembly(slot_of_i, slot_of_j, d, num_owned);
  for (std::size_t k = 0; k < measurements.size(); ++k)
    assembly.add_measurement(*measurements[k], slot_of_i[k], slot_of_j[k]);
  return assembly.emit(num_owned, num_slots);
}

SparseMatrix build_data_matrix(const std::vector<const Measurement*>& measurements,
                               const std::vector<std::size_t>& slot_of_i,
                               const std::vector<std::size_t>& slot_of_j, int d,
                               std::size_t num_slots) {
  return build_data_matrix_blocks(measurements, slot_of_i, slot_of_j, d, num_slots, num_slots).own;
}

SparseMatrix build_data_matrix(const std::vector<Measurement>& measurements, int d,
                               std::size_t num_poses) {
  std::vector<const Measurement*> ptrs;
  std::vector<std::size_t> si, sj;
  ptrs.reserve(measurements.size());
  si.reserve(measurements.size());
  sj.reserve(measurements.size());
  for (const auto& m : measurements) {
    ptrs.push_back(&m);
    si.push_back(m.i);
    sj.push_back(m.j);
  }
  return build_data_matrix(ptrs, si, sj, d, num_poses);
}

}  // namespace tessera
