#pragma once
// How the poses of a graph are named in the file they came from: their ids (any 64-bit
// values, in any order), the robot each belongs to, its timestamp and the fixed pose. The
// solvers only ever see dense ids 0..n-1; this mapping stays at the I/O boundary so that
// everything written back (g2o, TUM) uses the input's names, never a renumbering.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace tessera {

/// How a 64-bit id names a robot.
enum class KeyScheme {
  kPlain,         ///< Plain numbers: one robot, named "0"; a pose's index is its id.
  kGtsam,         ///< gtsam::Symbol: robot = character in bits 56-63, index = bits 0-55.
  kGtsamLabeled,  ///< gtsam::LabeledSymbol: one character in bits 56-63 for every pose,
                  ///< robot = label character in bits 48-55, index = bits 0-47.
};

/// "plain", "gtsam" or "gtsam-labeled".
const char* key_scheme_name(KeyScheme scheme);

/// The GTSAM key of pose `index` of robot `robot` ('a' << 56 | index).
std::uint64_t gtsam_key(char robot, std::uint64_t index);

/// Whether `id` reads as a gtsam::Symbol of a robot: its top byte is a letter A-Z or a-z.
bool is_gtsam_key(std::uint64_t id);

struct PoseKeys {
  KeyScheme scheme = KeyScheme::kPlain;
  /// ids[k]: the input's id of dense pose k, strictly increasing. Empty: ids are 0..n-1.
  std::vector<std::uint64_t> ids;
  /// robot[k]: robot of dense pose k (an index into robot_names). Empty: one robot.
  std::vector<std::uint32_t> robot;
  /// Name of each robot (gtsam: its character). Empty: one robot named "0".
  std::vector<std::string> robot_names;
  /// stamps[k]: timestamp of dense pose k in seconds. Empty: no timestamps.
  std::vector<double> stamps;
  /// Dense index of the pose a FIX line holds at its VERTEX value (the first FIX id).
  std::optional<std::size_t> fixed;

  std::uint64_t id(std::size_t k) const { return ids.empty() ? k : ids[k]; }
  std::size_t num_robots() const { return robot_names.empty() ? 1 : robot_names.size(); }
  std::uint32_t robot_of(std::size_t k) const { return robot.empty() ? 0 : robot[k]; }
  std::string robot_name(std::size_t r) const {
    return robot_names.empty() ? std::string("0") : robot_names[r];
  }
  /// The pose's number inside its robot (gtsam: the key's index; plain: the id).
  std::uint64_t index_in_robot(std::size_t k) const;
  /// Dense index of input id `id`, or nothing when no pose has it.
  std::optional<std::size_t> find(std::uint64_t id) const;
};

/// Sets keys.scheme, keys.robot and keys.robot_names from keys.ids (n poses) by `scheme`.
/// Robots are numbered in the order of their names. Ids that do not fit the scheme must have
/// been refused by the caller (is_gtsam_key); kPlain makes one robot.
void assign_robots(PoseKeys& keys, std::size_t n, KeyScheme scheme);

/// The scheme an automatic detection picks for these ids: gtsam when every id has a letter
/// in its top byte (kGtsamLabeled when that letter is the same for all and bits 48-55 are
/// letters too, not all equal), plain otherwise.
KeyScheme detect_key_scheme(const PoseKeys& keys, std::size_t n);

}  // namespace tessera
