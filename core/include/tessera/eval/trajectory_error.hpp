#pragma once
// Accuracy of an estimated trajectory against ground truth, as evo and the SLAM literature
// report it: absolute trajectory error (ATE: position error after aligning the estimate to
// the truth) and relative pose error (RPE: translation error of the motion over `delta`
// poses, which no alignment changes). Per robot and over the team (one alignment for all).

#include <cstddef>
#include <string>
#include <tessera/eval/alignment.hpp>
#include <tessera/eval/trajectory.hpp>
#include <vector>

namespace tessera {

struct TrajectoryErrorOptions {
  /// se3 (default; SE(2) for 2D trajectories), sim3 (also a scale) or none.
  AlignMode align = AlignMode::kSe3;
  /// RPE over pose k and pose k + delta of one robot (in matched order), >= 1.
  std::size_t delta = 1;
  /// Largest |stamp difference| in seconds for two poses to match when both sides have
  /// stamps, >= 0 and finite.
  double stamp_tolerance = 0.01;

  /// Throws InputError naming the field when one is out of range.
  void validate() const;
};

/// RMSE, mean, median and maximum of a list of errors (metres); all 0 for no errors.
struct ErrorStats {
  double rmse = 0, mean = 0, median = 0, max = 0;
  std::size_t count = 0;
};
ErrorStats error_stats(std::vector<double> errors);

struct RobotError {
  std::string name;
  std::size_t matched = 0;  ///< Poses matched between estimate and truth.
  ErrorStats ate, rpe;
};

struct TrajectoryErrorResult {
  ErrorStats ate, rpe;             ///< Over the team.
  std::vector<RobotError> robots;  ///< In the estimate's robot order.
  Alignment alignment;             ///< Estimate -> truth (d = the trajectories' dimension).
  int d = 3;
  std::string matched_by;  ///< "stamp" or "index".
  std::size_t matched = 0;
  std::size_t unmatched_estimate = 0;  ///< Estimate poses with no partner in the truth.
};

/// Matches the poses of `estimate` and `truth` robot by robot (by name; two single-robot
/// trajectories match whatever their names), then pose by pose: by stamp within the
/// tolerance when both have stamps, by index otherwise. Throws InputError when a robot of
/// the estimate is missing in the truth or fewer poses match than the alignment needs
/// (d; one without alignment).
TrajectoryErrorResult trajectory_error(const Trajectory& estimate, const Trajectory& truth,
                                       const TrajectoryErrorOptions& options = {});

}  // namespace tessera
