#pragma once
// Measurements carried in a PoseBlockMessage, for the steps that send measurement values
// between agents over the round protocol's channel (the chordal initialization stage, a
// robust run's fresh start of the kept set): one entry per measurement at rank 4,
// [i, j, kappa, tau, R, t] (R column-major, graph/flat_measurement.hpp), zero-padded to the
// entry's 4 (d + 1) doubles; pose_ids carries the measurement's position in the file.

#include <cstdint>
#include <tessera/graph/measurement.hpp>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

namespace tessera {

constexpr std::uint32_t kMeasurementBlockRank = 4;

/// The block of `measurements` (their file positions in `index`, below 2^32: std::runtime_error
/// otherwise) from `sender` at `phase`.
PoseBlockMessage encode_measurement_block(std::uint32_t sender, std::uint32_t phase, int d,
                                          const std::vector<const Measurement*>& measurements,
                                          const std::vector<std::uint64_t>& index);

/// Appends (file position, measurement) of every entry of `block` to `out`. Throws
/// std::runtime_error (naming `what` and the sender) on a malformed block or a pose id outside
/// 0..num_poses-1.
void decode_measurement_block(const PoseBlockMessage& block, int d, std::size_t num_poses,
                              const char* what,
                              std::vector<std::pair<std::uint64_t, Measurement>>& out);

}  // namespace tessera
