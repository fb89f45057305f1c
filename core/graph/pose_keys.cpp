#include <algorithm>
#include <map>
#include <tessera/graph/pose_keys.hpp>

namespace tessera {
namespace {

constexpr std::uint64_t kIndex56 = (std::uint64_t{1} << 56) - 1;
constexpr std::uint64_t kIndex48 = (std::uint64_t{1} << 48) - 1;

bool is_letter(unsigned c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
unsigned top_byte(std::uint64_t id) {
  return static_cast<unsigned>(id >> 56);
}
unsigned label_byte(std::uint64_t id) {
  return static_cast<unsigned>((id >> 48) & 0xff);
}

}  // namespace

const char* key_scheme_name(KeyScheme scheme) {
  switch (scheme) {
    case KeyScheme::kGtsam:
      return "gtsam";
    case KeyScheme::kGtsamLabeled:
      return "gtsam-labeled";
    case KeyScheme::kPlain:
      break;
  }
  return "plain";
}

std::uint64_t gtsam_key(char robot, std::uint64_t index) {
  return static_cast<std::uint64_t>(static_cast<unsigned char>(robot)) << 56 | (index & kIndex56);
}

bool is_gtsam_key(std::uint64_t id) {
  return is_letter(top_byte(id));
}

std::uint64_t PoseKeys::index_in_robot(std::size_t k) const {
  const std::uint64_t v = id(k);
  switch (scheme) {
    case KeyScheme::kGtsam:
      return v & kIndex56;
    case KeyScheme::kGtsamLabeled:
      return v & kIndex48;
    case KeyScheme::kPlain:
      break;
  }
  return v;
}

std::optional<std::size_t> PoseKeys::find(std::uint64_t v) const {
  if (ids.empty()) return std::nullopt;  // (callers check v < n themselves for dense ids)
  auto it = std::lower_bound(ids.begin(), ids.end(), v);
  if (it == ids.end() || *it != v) return std::nullopt;
  return static_cast<std::size_t>(it - ids.begin());
}

KeyScheme detect_key_scheme(const PoseKeys& keys, std::size_t n) {
  if (n == 0 || keys.ids.empty()) return KeyScheme::kPlain;  // ids 0..n-1: plain numbers
  bool all_letters = true, all_labels = true, labels_differ = false;
  const unsigned first_top = top_byte(keys.ids[0]), first_label = label_byte(keys.ids[0]);
  bool same_top = true;
  for (std::uint64_t id : keys.ids) {
    all_letters = all_letters && is_letter(top_byte(id));
    same_top = same_top && top_byte(id) == first_top;
    all_labels = all_labels && is_letter(label_byte(id));
    labels_differ = labels_differ || label_byte(id) != first_label;
  }
  if (!all_letters) return KeyScheme::kPlain;
  return same_top && all_labels && labels_differ ? KeyScheme::kGtsamLabeled : KeyScheme::kGtsam;
}

void assign_robots(PoseKeys& keys, std::size_t n, KeyScheme scheme) {
  keys.scheme = scheme;
  keys.robot.clear();
  keys.robot_names.clear();
  if (scheme == KeyScheme::kPlain) return;
  std::map<unsigned, std::uint32_t> number;  // robot character -> robot number
  auto robot_char = [&](std::size_t k) {
    return scheme == KeyScheme::kGtsam ? top_byte(keys.id(k)) : label_byte(keys.id(k));
  };
  for (std::size_t k = 0; k < n; ++k) number.emplace(robot_char(k), 0);
  for (auto& [c, r] : number) {
    r = static_cast<std::uint32_t>(keys.robot_names.size());
    keys.robot_names.push_back(std::string(1, static_cast<char>(c)));
  }
  keys.robot.resize(n);
  for (std::size_t k = 0; k < n; ++k) keys.robot[k] = number[robot_char(k)];
}

}  // namespace tessera
