#pragma once
// The agents' Newton trial points of one online solve, gathered per trial, so that the step's
// accepted Newton points can be kept (OnlineEngine::keep_step_points) without the agents keeping
// copies of their iterates.

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <mutex>
#include <tessera/distributed/newton_refine_result.hpp>
#include <tessera/distributed/trial_point_watch.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/online/step_points.hpp>
#include <vector>

namespace tessera {

/// Collects the blocks TrialPointWatch reports: agent b's k-th call is the k-th step of its
/// refinements' traces, the same steps on every agent.
class TrialPoints {
 public:
  /// `blocks` agents; `wall_s` and `cpu_s` time a trial (the step's clocks), read when a block
  /// arrives: a trial point exists once its last block does. `factorizations(b)`: block b's
  /// tangent factorizations so far (AgentState::tangent_factorizations_total), read here and
  /// on b's own thread when its block arrives; `earlier`: the step's factorizations before
  /// the solve. A trial's factorizations are `earlier` plus every block's since here.
  TrialPoints(int blocks, std::function<double()> wall_s, std::function<double()> cpu_s,
              std::function<long long(int)> factorizations, long long earlier);

  /// The watch to give the solve. It refers to this object, which must outlive the solve.
  TrialPointWatch watch();

  /// Appends the accepted trials of `refines` to `out` as points over `X` (stream ids; the linked
  /// poses' columns replaced through `blocks`). Throws std::logic_error if the trials seen do not
  /// match the refinements' steps or an accepted trial lacks a block.
  void accepted(const std::vector<NewtonRefineResult>& refines, const LiveBlocks& blocks,
                const Eigen::MatrixXd& X, std::vector<StepPoint>& out) const;

 private:
  struct Trial {
    std::vector<Eigen::MatrixXd> blocks;
    int received = 0;
    double wall_s = 0.0, cpu_s = 0.0;
    long long factorizations = 0;
  };
  int blocks_;
  std::function<double()> wall_s_, cpu_s_;
  std::function<long long(int)> factorizations_;
  std::vector<long long> factorizations_before_;  // by block, at construction
  long long earlier_;
  std::mutex mutex_;  // the watch is called concurrently for different agents
  std::vector<std::size_t> calls_;
  std::vector<Trial> trials_;
};

}  // namespace tessera
