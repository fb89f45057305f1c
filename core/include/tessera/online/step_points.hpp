#pragma once
// The estimates an online step passes through, and how soon one of them is close enough to the
// optimum. The gradient tolerance says when a step is done; the latency target asks
// instead how soon after the data arrived the estimate is within a relative bound of the optimum
// of the graph received so far, which an estimate can reach long before its gradient is back
// under the tolerance. Within a step the estimate changes at a few points only: when the new
// data are absorbed (new poses composed and placed, before any solve), at each accepted Newton
// step, and at the step's end (after any rounds). OnlineEngine::keep_step_points records those
// points with their times; the optimum of the graph received is known only offline, so the
// points are costed after the step (cost_step_points) and compared with it later (gap_latency).

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// Where in its step an estimate was, and when: what a kept point (StepPoint) and its costed
/// form (StepPointCost) share.
struct StepMark {
  /// "absorbed": the new data taken in, before any solve; "newton": an accepted Newton step's
  /// point; "end": where the step ended (after the rounds that follow Newton steps that stopped
  /// above the tolerance, or the rounds of a rounds-only step).
  std::string at;
  /// Since the step began, on OnlineUpdate's clocks: wall seconds (wall_s) and process CPU
  /// seconds (cpu_s). A Newton step's point is timed when the last agent formed its trial point,
  /// its sums on the way out: the verdict that accepts it comes one all-agent sum later. The
  /// "end" point has the step's own times, so no point is later than the step.
  double wall_s = 0.0, cpu_s = 0.0;
  /// The step's Newton steps (accepted or not) and their CG iterations up to this point: its
  /// load-free cost (0 at "absorbed"; OnlineUpdate's newton_steps and newton_cg_iterations at
  /// "end").
  int newton_steps = 0, cg_iterations = 0;
  /// The blocks' tangent factorizations in the step up to this point (set-up and Newton
  /// steps; OnlineUpdate::factorizations at "end"): the fixed cost a point waited for, free
  /// of the machine's load.
  long long factorizations = 0;
};

/// One estimate of a step (OnlineEngine::keep_step_points).
struct StepPoint : StepMark {
  Eigen::MatrixXd X;  ///< The lifted iterate (r x (d+1)n, stream ids).
};

/// A point's estimate and its cost (cost_step_points).
struct StepPointCost : StepMark {
  double cost = 0.0;  ///< Objective of the rounded estimate (reference convention).
};

/// Each point rounded to SE(d) (round_solution, as OnlineEngine::estimate) and its cost on
/// `graph`, the graph of the step the points come from. `graph` must be connected (one
/// frame to round in).
std::vector<StepPointCost> cost_step_points(const PoseGraph& graph,
                                            const std::vector<StepPoint>& points);

/// How soon a step's estimate came within `bound` of `optimum` (gap_latency).
struct GapLatency {
  std::vector<double> rel_gaps;  ///< (cost - optimum) / optimum at each point, in order.
  /// The first point within the bound, and the first from which every later point is
  /// (nullopt: none; the step ended above the bound).
  std::optional<std::size_t> first, stays;
  /// wait_s plus the first point's wall (CPU) time; +infinity when none.
  double wall_s = 0.0, cpu_s = 0.0;
};

/// The first of a step's `points` (in time order) whose relative gap to `optimum` is at most
/// `bound`. `wait_s`: from the data's publication to the step's start (stream clock).
GapLatency gap_latency(const std::vector<StepPointCost>& points, double optimum, double bound,
                       double wait_s);

}  // namespace tessera
