#pragma once
// Which probe the distributed GNC runs next after its re-check passes when cluster probes are on
// (GncDistributedOptions::cluster_probes): the distributed counterpart of the centralized search
// (cluster_probes.hpp), in the same order. First a tail probe (the kept measurements the agents
// name by their own residual tails leave, the return band comes back), then every run GNC
// partly cut together, then one cluster of kept closures side by side at a time
// (closure_clusters.hpp), then two clusters that share a stretch
// together (each raised the TLS cost alone), last the return band together, then one closure of
// it at a time. Each probe is judged by the summed TLS cost (GncProbes::keeps); a kept one makes
// every kind possible again, the return band together first.
//
// Who decides: every agent runs this search on the same data and so picks the same probe with
// no message of its own. A cluster is a property of the endpoints of the kept closures (every
// agent holds the endpoints of every measurement, GncAgentInput::structure, for the block
// layout and the connectivity check) and of the rejected set (the same on every agent after each
// verdict exchange); the tail and return lists are every agent's verdict lists, gathered by the
// verdict exchange (each measurement named by its weight owner); the TLS costs that keep or
// refuse a probe are the summed votes, added in agent-id order. The flips a probe makes are then
// applied by every agent alike, so both ends of a cut measurement keep the same weight.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <utility>
#include <vector>

namespace tessera {

class GncClusterSearch {
 public:
  /// `structure`: the endpoints of every measurement, file order; `known`: one flag per
  /// measurement (never a candidate). `tail_budget`: most tail probes (RobustOptions::
  /// recheck_probes); `budget`: most cluster, pair and return probes (cluster_probes, >= 1).
  GncClusterSearch(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
                   std::vector<bool> known, int tail_budget, int budget,
                   ClosureClusterOptions clusters);

  /// The verdict list at the state the next probes start from (every agent's RecheckVerdict::
  /// probe, any order), whose rejected ones are the return band, and the tail probe's flips
  /// (GncProbeStage::flips: the list, or only its rejected ones where GNC's own set keeps its
  /// tail). Called at every state that a probe does not undo (the first one, and after each
  /// kept probe).
  void set_list(const std::vector<std::uint64_t>& listed, const std::vector<std::uint64_t>& tail);
  /// The measurements the next probe flips (kept ones leave, rejected ones come back;
  /// ascending), from the set `rejected` (ascending), or nullopt when the search is over.
  std::optional<std::vector<std::uint64_t>> next(const std::vector<std::uint64_t>& rejected);
  /// The running probe stayed: the set changed, every candidate may be tried again.
  void kept();
  /// The running probe was undone, its TLS cost `rise` above the state's `base` (0 when it was
  /// undone before a verdict could judge it).
  void refused(double rise, double base);

  int tail_probes() const { return tail_used_; }
  int probes() const { return used_; }  ///< Cluster, pair and return probes.

 private:
  using Probe = ClusterUnion;  // the runs a probe cuts, and their members (ascending)
  bool untried(const std::vector<std::size_t>& members) const;
  std::optional<Probe> next_cluster(const std::vector<std::uint64_t>& rejected) const;

  PoseGraph skeleton_;  // the endpoints alone: what closure_clusters() reads
  std::vector<bool> known_;
  int tail_budget_, budget_;
  ClosureClusterOptions clusters_;
  std::vector<std::uint64_t> listed_, tail_;  // ascending
  int tail_used_ = 0, used_ = 0;
  bool tail_tried_ = false;
  std::vector<std::vector<std::size_t>> tried_;
  std::vector<std::pair<double, Probe>> raised_;
  std::optional<Probe> running_;  // the running probe when it is a cluster or pair probe
  bool returned_together_ = false;
  bool band_first_ = false;  // a probe stayed: the return band together comes first
  std::vector<std::uint64_t> returned_alone_;
};

}  // namespace tessera
