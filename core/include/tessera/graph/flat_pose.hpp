#pragma once
// The flat layout of poses in messages and checkpoints: a pose in SE(d) is d*(d+1) doubles,
// R column-major (R(r, c) at c*d + r) then t. One definition for every writer and reader
// (DDS wire types, the agents' initialisation stage), so the two sides always agree.

#include <cstddef>
#include <tessera/graph/pose.hpp>
#include <vector>

namespace tessera {

/// Doubles one pose of dimension `d` takes: d*(d+1).
constexpr std::size_t flat_pose_size(int d) {
  return static_cast<std::size_t>(d) * static_cast<std::size_t>(d + 1);
}

/// Appends `pose` in the flat layout. With `width` > flat_pose_size(d), pads with zeros to
/// `width` values (slots a caller fills with extra per-pose data); `width` smaller than
/// the pose is an error (std::invalid_argument).
void append_flat_pose(std::vector<double>& out, const Pose& pose, std::size_t width = 0);

/// The pose of dimension `d` whose values start at `data[offset]`. Throws
/// std::out_of_range when `data` ends before the pose does.
Pose read_flat_pose(const std::vector<double>& data, std::size_t offset, int d);

}  // namespace tessera
