#pragma once
// The coordinator's side of agents that die during the rounds (docs/fault-tolerance.md): it
// feeds the session's lost peers, the restarted agents' REJOIN requests and the round
// statuses to the RejoinArbiter (the one decision point, rejoin_arbiter.hpp), and acts on
// its decisions on the wire: a ROLLBACK order to every agent, a re-partition among the
// survivors (with --replicas), or a clean stop naming the lost agent. Events go to the
// operator's status monitor when there is one, to stderr otherwise.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

#include "coordinator/coordinator_options.hpp"
#include "runtime/rejoin_arbiter.hpp"
#include "runtime/run_monitor.hpp"
#include "tessera.h"
#include "transport/coordinator_session.hpp"

namespace tessera::coordinator {

/// The assignment in force and what the faults did to it (for the merge and the summary).
struct LossRecord {
  std::uint32_t epoch = 0;                     ///< > 0 after a re-partition for the survivors.
  std::vector<std::uint32_t> owner;            ///< Agent of every pose, as now assigned.
  std::vector<std::uint32_t> expected;         ///< Agents whose final estimates count, ascending.
  std::vector<std::uint32_t> lost;             ///< Agents lost for good.
  std::uint32_t last_round = 0;                ///< Last round status seen before the loss.
  std::size_t moved_poses = 0, cut_edges = 0;  ///< Of the re-partition.
  double at_ms = 0;                            ///< Re-partition time since the rounds started.
  std::uint32_t rollbacks = 0;                 ///< Coordinated rollbacks (agents that rejoined).
};

class LossHandling {
 public:
  using Clock = std::chrono::steady_clock;
  /// What a watch() step changed for the round statuses still in flight.
  enum class Outcome {
    kNone,
    kRolledBack,     ///< Partial sums of abandoned rounds are void.
    kRepartitioned,  ///< The survivors' run starts reporting again (new final report).
  };

  /// `base`: the assignment the agents received (its owner map is the one in force);
  /// `graph`: the run's structure, for the survivors' re-partition; `monitor` may be null.
  /// With --rejoin-timeout or --replicas, makes the session tolerate lost agents.
  LossHandling(const CoordinatorOptions& options, transport::CoordinatorSession& session,
               const GraphStructure& graph, const wire::PartitionAssignment& base,
               RunMonitor* monitor, Clock::time_point t_run);

  /// Whether lost agents are arbitrated (waited for / replaced) rather than fatal.
  bool arbitrates() const { return arbitrate_; }
  /// Round statuses of older epochs are from before a rollback or re-partition: ignore them.
  std::uint32_t status_epoch() const { return std::max(arbiter_.epoch(), record_.epoch); }
  /// A round status from protocol id `sender` (after a re-partition: a position among the
  /// survivors) for `round`.
  void on_round_status(std::uint32_t sender, std::uint32_t round, Clock::time_point now);
  /// Polls the session's lost agents and REJOIN requests and acts on the arbiter's decision.
  /// Throws RunFailure when the run must stop (nobody to take over, a second loss).
  Outcome watch(Clock::time_point now);

  const LossRecord& record() const { return record_; }

 private:
  void check_second_loss(const std::vector<std::uint32_t>& lost, Clock::time_point now);
  Outcome decide(Clock::time_point now);
  Outcome repartition(const LossDecision& d, Clock::time_point now);
  void report(const std::string& what, Clock::time_point now);

  const CoordinatorOptions& options_;
  transport::CoordinatorSession& session_;
  const GraphStructure& graph_;
  wire::PartitionAssignment base_;
  RunMonitor* monitor_;
  Clock::time_point t_run_;
  RejoinArbiter arbiter_;
  bool arbitrate_;
  LossRecord record_;
  std::map<std::uint32_t, Clock::time_point> second_;  // survivors lost since
};

}  // namespace tessera::coordinator
