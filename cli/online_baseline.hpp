#pragma once
// `tessera solve GRAPH --online --baseline`: the CPU time of re-solving from scratch after every
// loop closure, the yardstick of issue 24 ("total agent CPU over the replay at most a tenth of
// re-solving from scratch after every loop closure"; docs/online.md, "What the baseline is").
//
// Per publication (--baseline-per publication, the default): once after every batch a front end
// published with loop closures in it, on the graph published up to and with that batch; closures
// that arrive together share one re-solve. Per closure: once per closure measurement, on the graph
// up to and with it. Per step: once per step of the online run that brought a closure, on the
// graph at the end of the step (fewer re-solves when steps are long). A lagging copy of the stream
// absorbs the same batches one at a time, so each graph is known exactly, not only the step's.
// Each re-solve: the same agents and blocks as the online run, from the chordal initialization
// (where the graph is connected) or the front ends' guesses, to the run's tolerance, without
// certificate, with the online steps' Newton steps or the batch solver's rounds.

#include <cstddef>
#include <functional>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <vector>

#include "arguments.hpp"
#include "json_writer.hpp"

namespace tessera::cli {

/// One re-solve of the baseline: the agents from `initial` (empty: the solver's chordal
/// initialization) to the online run's tolerance, without certificate. newton: the online
/// steps' solver (Newton steps from the start, rounds after them if they stop short), else the
/// batch solver's rounds. Not inlined: `scripts/bench/online.py --instructions` counts the
/// instructions inside it.
DistributedResult resolve_from_scratch(const PoseGraph& g, const std::vector<int>& assignment,
                                       const OnlineOptions& options, bool newton,
                                       const std::vector<Pose>& initial);

class OnlineBaseline {
 public:
  /// Reads --baseline, --baseline-per, --baseline-init, --baseline-solver, --baseline-every
  /// and --baseline-samples (InputError naming the option for a bad value). `plan`: the
  /// replay the online run plays (it must outlive this object).
  OnlineBaseline(const Arguments& args, const ReplayPlan& plan, int d,
                 const OnlineOptions& options);

  /// After each online step that did work (run_online's observer): re-solves what the step
  /// brought, sampled. Nothing without --baseline.
  void observe(const OnlineEngine& engine, const OnlineUpdate& update);
  /// The `baseline_*` fields of the JSON summary (nothing without --baseline).
  void add_to(JsonObject& json) const;
  /// For progress lines: re-solves done, the number the run will do (about), and their
  /// process CPU so far (0 without --baseline).
  int resolved() const { return sampled_; }
  long expected() const {  // the middle of every stride of every_ (consider)
    return enabled_ && counted_ > every_ / 2 ? (counted_ - every_ / 2 - 1) / every_ + 1 : 0;
  }
  double measured_cpu_s() const { return cpu_s_; }
  /// Called before each re-solve with its graph's poses and measurements (progress lines).
  std::function<void(std::size_t, std::size_t)> before_resolve;

 private:
  void resolve(const PoseGraph& g, const std::vector<int>& assignment,
               const std::vector<Pose>& guesses);
  // Re-solves (sampled) the lagging stream's poses with its first `count` measurements.
  void consider(const OnlineEngine& engine, std::size_t count);
  // Marks the poses of the lagging stream's measurements up to `count` as linked; true when
  // every pose of the lagging stream is (incremental: O(new measurements and poses) a call).
  bool every_pose_linked_up_to(std::size_t count);

  const ReplayPlan& plan_;
  OnlineOptions options_;
  bool enabled_ = false;
  std::string per_, init_, solver_;
  long every_ = 1;
  double cpu_s_ = 0.0;
  int solves_ = 0, sampled_ = 0, rounds_ = 0, cg_ = 0, chordal_ = 0;
  std::size_t closures_ = 0, publications_ = 0, closure_steps_ = 0, skipped_ = 0;
  long counted_ = 0;  // publications or closures in the replay (what --baseline-samples splits)
  GraphStream lag_;
  std::size_t lag_next_ = 0;
  std::vector<char> linked_;  // per pose of the lagging stream: some measurement touches it
  std::size_t unlinked_ = 0, linked_measurements_ = 0;
};

}  // namespace tessera::cli
