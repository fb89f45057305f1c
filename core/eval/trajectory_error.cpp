#include <algorithm>
#include <cmath>
#include <tessera/eval/trajectory_error.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

namespace tessera {
namespace {

struct Match {
  const TrajectoryPose* est;
  const TrajectoryPose* truth;
};

const RobotTrajectory* partner(const RobotTrajectory& est, const Trajectory& estimate,
                               const Trajectory& truth) {
  if (estimate.robots.size() == 1 && truth.robots.size() == 1) return &truth.robots[0];
  for (const auto& r : truth.robots)
    if (r.name == est.name) return &r;
  return nullptr;
}

// Pairs of poses of one robot, in the estimate's order.
std::vector<Match> match_robot(const RobotTrajectory& est, const RobotTrajectory& truth,
                               bool by_stamp, double tolerance) {
  std::vector<Match> out;
  if (by_stamp) {
    std::vector<const TrajectoryPose*> sorted;
    for (const auto& p : truth.poses) sorted.push_back(&p);
    std::sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->stamp < b->stamp; });
    for (const auto& p : est.poses) {
      auto it = std::lower_bound(sorted.begin(), sorted.end(), p.stamp,
                                 [](auto* q, double s) { return q->stamp < s; });
      const TrajectoryPose* best = nullptr;
      for (auto c : {it, it == sorted.begin() ? it : it - 1})
        if (c != sorted.end() &&
            (!best || std::abs((*c)->stamp - p.stamp) < std::abs(best->stamp - p.stamp)))
          best = *c;
      if (best && std::abs(best->stamp - p.stamp) <= tolerance) out.push_back({&p, best});
    }
  } else {
    std::vector<const TrajectoryPose*> sorted;
    for (const auto& p : truth.poses) sorted.push_back(&p);
    std::sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->index < b->index; });
    for (const auto& p : est.poses) {
      auto it = std::lower_bound(sorted.begin(), sorted.end(), p.index,
                                 [](auto* q, std::uint64_t i) { return q->index < i; });
      if (it != sorted.end() && (*it)->index == p.index) out.push_back({&p, *it});
    }
  }
  return out;
}

}  // namespace

void TrajectoryErrorOptions::validate() const {
  if (delta < 1) throw InputError("TrajectoryErrorOptions.delta (--delta) must be >= 1");
  if (!(std::isfinite(stamp_tolerance) && stamp_tolerance >= 0))
    throw InputError(
        "TrajectoryErrorOptions.stamp_tolerance (--tolerance) must be finite and >= 0");
}

ErrorStats error_stats(std::vector<double> e) {
  ErrorStats s;
  s.count = e.size();
  if (e.empty()) return s;
  double sum = 0, sq = 0;
  for (double x : e) {
    sum += x;
    sq += x * x;
    s.max = std::max(s.max, x);
  }
  s.mean = sum / static_cast<double>(e.size());
  s.rmse = std::sqrt(sq / static_cast<double>(e.size()));
  std::sort(e.begin(), e.end());
  const std::size_t h = e.size() / 2;
  s.median = e.size() % 2 ? e[h] : 0.5 * (e[h - 1] + e[h]);
  return s;
}

TrajectoryErrorResult trajectory_error(const Trajectory& estimate, const Trajectory& truth,
                                       const TrajectoryErrorOptions& options) {
  options.validate();
  TrajectoryErrorResult result;
  const int d = estimate.d == 2 && truth.d == 2 ? 2 : 3;
  result.d = d;
  bool by_stamp = true;
  for (const auto* t : {&estimate, &truth})
    for (const auto& r : t->robots) by_stamp = by_stamp && r.has_stamps;
  result.matched_by = by_stamp ? "stamp" : "index";

  std::vector<std::vector<Match>> matches;
  for (const auto& r : estimate.robots) {
    const RobotTrajectory* other = partner(r, estimate, truth);
    if (!other)
      throw InputError(
          truth.source, 0,
          "has no robot '" + r.name + "' (the estimate " + estimate.source + " has it)");
    matches.push_back(match_robot(r, *other, by_stamp, options.stamp_tolerance));
    result.matched += matches.back().size();
    result.unmatched_estimate += r.poses.size() - matches.back().size();
  }
  // An alignment needs d matched positions to fix a rotation (3 non-collinear in 3D).
  const std::size_t needed = options.align == AlignMode::kNone ? 1 : static_cast<std::size_t>(d);
  if (result.matched < needed)
    throw InputError(estimate.source, 0,
                     "only " + std::to_string(result.matched) + " of its poses match " +
                         truth.source + " by " + result.matched_by + " (need at least " +
                         std::to_string(needed) + ")");

  Eigen::MatrixXd from(d, result.matched), to(d, result.matched);
  std::size_t c = 0;
  for (const auto& ms : matches)
    for (const auto& m : ms) {
      from.col(c) = m.est->t.head(d);
      to.col(c++) = m.truth->t.head(d);
    }
  result.alignment = umeyama_alignment(from, to, options.align);
  const Alignment& a = result.alignment;
  Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity();
  R3.topLeftCorner(d, d) = a.R;
  Eigen::Vector3d t3 = Eigen::Vector3d::Zero();
  t3.head(d) = a.t;

  std::vector<double> team_ate, team_rpe;
  for (std::size_t r = 0; r < matches.size(); ++r) {
    RobotError re;
    re.name = estimate.robots[r].name;
    re.matched = matches[r].size();
    std::vector<double> ate, rpe;
    // The aligned estimate: x -> scale R x + t, rotations R R_k.
    std::vector<std::pair<Eigen::Matrix3d, Eigen::Vector3d>> est;
    for (const auto& m : matches[r]) {
      est.emplace_back(R3 * m.est->R, a.scale * (R3 * m.est->t) + t3);
      ate.push_back((m.truth->t - est.back().second).norm());
    }
    const std::size_t k_delta = options.delta;
    for (std::size_t k = 0; k + k_delta < matches[r].size(); ++k) {
      const TrajectoryPose& g0 = *matches[r][k].truth;
      const TrajectoryPose& g1 = *matches[r][k + k_delta].truth;
      // Motion from pose k to pose k + delta, in pose k's frame, of each side.
      const Eigen::Vector3d dt_truth = g0.R.transpose() * (g1.t - g0.t);
      const Eigen::Matrix3d dR_truth = g0.R.transpose() * g1.R;
      const Eigen::Vector3d dt_est =
          est[k].first.transpose() * (est[k + k_delta].second - est[k].second);
      // Error E = delta_truth^-1 delta_est: its translation is dR_truth^T (dt_est - dt_truth).
      rpe.push_back((dR_truth.transpose() * (dt_est - dt_truth)).norm());
    }
    team_ate.insert(team_ate.end(), ate.begin(), ate.end());
    team_rpe.insert(team_rpe.end(), rpe.begin(), rpe.end());
    re.ate = error_stats(std::move(ate));
    re.rpe = error_stats(std::move(rpe));
    result.robots.push_back(std::move(re));
  }
  result.ate = error_stats(std::move(team_ate));
  result.rpe = error_stats(std::move(team_rpe));
  return result;
}

}  // namespace tessera
