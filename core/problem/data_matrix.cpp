#include "problem/data_matrix.hpp"

#include <Eigen/Core>

namespace tessera {

SparseMatrix build_data_matrix(const std::vector<const Measurement*>& measurements,
                               const std::vector<std::size_t>& slot_of_i,
                               const std::vector<std::size_t>& slot_of_j, int d,
                               std::size_t num_slots) {
  using Index = Eigen::Index;
  const Index w = d + 1;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(measurements.size() * static_cast<std::size_t>(2 * d * d + 4 * d + 6));
  auto add = [&](Index r, Index c, double v) { triplets.emplace_back(r, c, v); };
  for (std::size_t k = 0; k < measurements.size(); ++k) {
    const Measurement& m = *measurements[k];
    const Index ri = w * static_cast<Index>(slot_of_i[k]);  // first rotation column of pose i
    const Index rj = w * static_cast<Index>(slot_of_j[k]);
    const Index ti = ri + d, tj = rj + d;                    // translation columns
    // Rotation term: kappa ||X A||^2 with A = [-R_ij at i; I at j].
    for (Index a = 0; a < d; ++a) {
      add(ri + a, ri + a, m.kappa);
      add(rj + a, rj + a, m.kappa);
      for (Index b = 0; b < d; ++b) {
        add(ri + a, rj + b, -m.kappa * m.R(a, b));
        add(rj + b, ri + a, -m.kappa * m.R(a, b));
      }
    }
    // Translation term: tau ||X a||^2 with a = [-t_ij at i rotation; -1 at i; +1 at j].
    for (Index a = 0; a < d; ++a) {
      for (Index b = 0; b < d; ++b) add(ri + a, ri + b, m.tau * m.t(a) * m.t(b));
      add(ri + a, ti, m.tau * m.t(a));
      add(ti, ri + a, m.tau * m.t(a));
      add(ri + a, tj, -m.tau * m.t(a));
      add(tj, ri + a, -m.tau * m.t(a));
    }
    add(ti, ti, m.tau);
    add(tj, tj, m.tau);
    add(ti, tj, -m.tau);
    add(tj, ti, -m.tau);
  }
  const Index size = w * static_cast<Index>(num_slots);
  SparseMatrix Q(size, size);
  Q.setFromTriplets(triplets.begin(), triplets.end());
  Q.makeCompressed();
  return Q;
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
