#pragma once
// The flat layout of a measurement's values in messages: R column-major (R(r, c) at c*d + r,
// d*d values) and t (d values), i.e. the flat pose (graph/flat_pose.hpp) of (R, t). One
// definition for every writer and reader (the hand-off's separate R and t arrays, the
// initialisation stage's one array per measurement), so the two sides always agree.

#include <cstddef>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera {

/// Appends e.R column-major to `rotations` and e.t to `translations`. Pass the same vector
/// twice to get R then t contiguous (the flat pose of (R, t)). i, j, kappa and tau are not
/// written: each message keeps them where its layout wants them.
void append_measurement_rt(std::vector<double>& rotations, std::vector<double>& translations,
                           const Measurement& e);

/// Sets e.R (d x d) from `rotations[r_offset..]` and e.t (d) from `translations[t_offset..]`,
/// the layout append_measurement_rt() writes. Throws std::out_of_range when an array ends
/// before its values do; leaves i, j, kappa and tau alone.
void read_measurement_rt(const std::vector<double>& rotations, std::size_t r_offset,
                         const std::vector<double>& translations, std::size_t t_offset, int d,
                         Measurement& e);

}  // namespace tessera
