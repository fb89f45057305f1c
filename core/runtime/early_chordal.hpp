#pragma once
// Agent 0's chordal initialization of the whole graph, started as soon as the agent has the
// graph in memory instead of after the readiness barrier.
//
// With `--init chordal` agent 0 solves the chordal initialization of the whole graph from the
// values every agent sends it (runtime/initialization_stage.hpp). Under `tessera launch` the
// fork server has already parsed the whole file that every agent's share comes from
// (runtime/preloaded_graph.hpp), so agent 0 can solve it while the processes discover each other
// and the coordinator partitions: that solve was the largest part of agent 0's work from the
// readiness barrier to the first round. The stage still gathers the values (nothing changes on the
// wire) and uses the early poses only when the gathered graph is the one solved, value for value;
// otherwise it solves the gathered graph as before. Same input, same deterministic solve: same
// poses.

#include <future>
#include <optional>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::agent {

class EarlyChordal {
 public:
  /// Starts chordal_initialization(graph) on a thread. `graph` must outlive this object (the
  /// preloaded graph lives as long as the process).
  explicit EarlyChordal(const PoseGraph& graph);
  /// Waits for the thread (its result is then dropped).
  ~EarlyChordal();
  EarlyChordal(const EarlyChordal&) = delete;
  EarlyChordal& operator=(const EarlyChordal&) = delete;

  /// Waits for the solve; its poses when `gathered` has the same d, poses and measurements
  /// (endpoints, values and weights, in the same order) as the graph it solved, else nullopt
  /// (also when the early solve failed: the stage then solves, and reports, the error itself).
  /// Once only: a second call returns nullopt.
  std::optional<std::vector<Pose>> take_if_same(const PoseGraph& gathered);

 private:
  const PoseGraph& graph_;
  std::future<std::vector<Pose>> poses_;
};

/// Whether `a` and `b` are the same chordal problem: d, number of poses and every measurement
/// (i, j, R, t, kappa, tau) equal, in the same order. Initial poses and sources are ignored
/// (the chordal solve does not read them).
bool same_chordal_problem(const PoseGraph& a, const PoseGraph& b);

}  // namespace tessera::agent
