#pragma once
// The 3D agents' measurement terms (block_problem.cpp's edge_term<3, 3>, at their 3 active rows)
// for several measurements at once, one a vector lane (four with AVX, two with SSE2;
// manifold/pose_lanes.hpp's pose_lanes()). Each lane does the per-measurement code's
// operations in its order, so every term has the same bits; the caller adds them up in order.

namespace tessera {

/// terms[l] = kappa ||X_j^R - X_i^R R||^2 + tau ||t_j - t_i - X_i^R t||^2 of measurement l of
/// a group of `lanes`: its poses at xi[l] and xj[l] (3 x 4, column-major), its packed
/// measurement (R column-major, t, kappa, tau: 14 doubles) at m + 14 l.
void edge_terms_in_lanes(const double* const* xi, const double* const* xj, const double* m,
                         int lanes, double* terms);

}  // namespace tessera
