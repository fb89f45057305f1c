#include <cmath>
#include <cstdio>
#include <tessera/generate/generator_options.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {

constexpr std::size_t kMaxPoses = 10'000'000;

struct KindName {
  TrajectoryKind kind;
  const char* name;
};
constexpr KindName kKindNames[] = {{TrajectoryKind::kGrid3d, "grid3d"},
                                   {TrajectoryKind::kSphere, "sphere"},
                                   {TrajectoryKind::kTorus, "torus"},
                                   {TrajectoryKind::kCity, "city"}};

struct OutlierKindName {
  OutlierKind kind;
  const char* name;
};
constexpr OutlierKindName kOutlierKindNames[] = {{OutlierKind::kRandom, "random"},
                                                 {OutlierKind::kGroup, "group"},
                                                 {OutlierKind::kInterRobot, "inter-robot"}};

std::string number_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

void require_in_range(const char* field, double value, double lo, double hi, const char* unit) {
  if (!(std::isfinite(value) && value >= lo && value <= hi))
    throw InputError("generator option " + std::string(field) + " = " + number_text(value) +
                     ": must be in [" + number_text(lo) + ", " + number_text(hi) + "]" + unit);
}

}  // namespace

const char* trajectory_kind_name(TrajectoryKind kind) {
  for (const auto& k : kKindNames)
    if (k.kind == kind) return k.name;
  return "unknown";
}

const char* outlier_kind_name(OutlierKind kind) {
  for (const auto& k : kOutlierKindNames)
    if (k.kind == kind) return k.name;
  return "unknown";
}

OutlierKind parse_outlier_kind(const std::string& name) {
  std::string valid;
  for (const auto& k : kOutlierKindNames) {
    if (name == k.name) return k.kind;
    valid += valid.empty() ? k.name : std::string(", ") + k.name;
  }
  throw InputError("unknown outlier kind '" + name + "' (valid kinds: " + valid + ")");
}

TrajectoryKind parse_trajectory_kind(const std::string& name) {
  std::string valid;
  for (const auto& k : kKindNames) {
    if (name == k.name) return k.kind;
    valid += valid.empty() ? k.name : std::string(", ") + k.name;
  }
  throw InputError("unknown trajectory kind '" + name + "' (valid kinds: " + valid + ")");
}

void GeneratorOptions::validate() const {
  if (num_poses < 2 || num_poses > kMaxPoses)
    throw InputError("generator option num_poses = " + std::to_string(num_poses) +
                     ": must be in [2, " + std::to_string(kMaxPoses) + "]");
  if (num_robots < 1 || num_robots > num_poses)
    throw InputError("generator option num_robots = " + std::to_string(num_robots) +
                     ": must be in [1, num_poses = " + std::to_string(num_poses) +
                     "] (every robot needs at least one pose)");
  require_in_range("loop_closure_probability", loop_closure_probability, 0.0, 1.0, "");
  require_in_range("inter_robot_closure_probability", inter_robot_closure_probability, 0.0, 1.0,
                   "");
  require_in_range("rotation_noise", rotation_noise, 0.0, 1.0, " rad");
  require_in_range("translation_noise", translation_noise, 0.0, 100.0, " m");
  require_in_range("outlier_fraction", outlier_fraction, 0.0, 0.9, "");
  if (outlier_kind_name(outlier_kind) == std::string("unknown"))
    throw InputError("generator option outlier_kind: not a known outlier kind");
  if (outlier_fraction > 0 && outlier_kind == OutlierKind::kInterRobot && num_robots < 2)
    throw InputError("generator option outlier_kind = inter-robot: needs num_robots >= 2 (got " +
                     std::to_string(num_robots) + ")");
  if (trajectory_kind_name(kind) == std::string("unknown"))
    throw InputError("generator option kind: not a known trajectory kind");
}

}  // namespace tessera
