#pragma once
// The 3D agents' measurement terms (block_problem.cpp's edge_term<3, 3>, at their 3 active rows)
// for several measurements at once, one a vector lane (four with AVX, two with SSE2;
// manifold/pose_lanes.hpp's pose_lanes()). Each lane does the per-measurement code's
// operations in its order, so every term has the same bits, and the terms are added up in
// measurement order as the one-by-one loop adds them.

#include <cstddef>

namespace tessera {

/// Adds the terms kappa ||X_j^R - X_i^R R||^2 + tau ||t_j - t_i - X_i^R t||^2 of the first
/// measurements, in whole groups, to f in order, and to s with the cut ones (a slot >= m)
/// halved. Measurement k: slots slots[2k], slots[2k + 1] (below m: X's pose, else Xn's pose
/// slot - m; 3 x 4, column-major), packed measurement (R column-major, t, kappa, tau: 14
/// doubles) at packed + 14 k. Returns how many measurements it did; the caller adds the rest.
std::size_t sum_edge_terms_in_lanes(const std::size_t* slots, std::size_t count, const double* X,
                                    const double* Xn, std::size_t m, const double* packed,
                                    double& f, double& s);

}  // namespace tessera
