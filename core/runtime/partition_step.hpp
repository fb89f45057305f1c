#pragma once
// The coordinator's one-shot partition, behind one function so the partitioner can be
// swapped without touching the runtime.

#include <cstdint>
#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

namespace tessera::coordinator {

struct PartitionStepResult {
  std::vector<std::uint32_t> owner;  ///< Agent of every pose.
  double ms = 0;                     ///< Wall time of the partitioning.
  /// CPU time of the thread that partitioned: the partitioner's own cost, which `ms` exceeds
  /// when the thread shares the cores with the agents starting up (file_partition.hpp).
  double cpu_ms = 0;
  /// How long the run waited for the partition once every agent had announced itself: its
  /// share of the run's critical path (0 when the file's partition ended first; = ms when
  /// the announced structure is partitioned).
  double wait_ms = 0;
  std::size_t cut_edges = 0;  ///< Measurements between different agents.
  bool early = false;         ///< Of the graph file, while the agents started (file_partition.hpp).
  /// The partitioning thread's nice minus the process's (0: the same; < 0 for the
  /// coordinator's early partition with --partition-nice, coordinator/partition_priority.hpp).
  int thread_nice = 0;
};

/// Splits the structure among `num_agents` agents with core's partitioner (`preset` as
/// parse_preset_for accepts: auto, sequential, fast, eco, strong, highest) and the `rounds`
/// objective.
/// `time_limit_s` > 0 caps the search's wall time (PartitionOptions::time_limit_s).
/// Throws InputError on a bad preset or more agents than poses.
PartitionStepResult partition_for_agents(const GraphStructure& graph, std::uint32_t num_agents,
                                         const std::string& preset, std::uint64_t seed,
                                         double time_limit_s = 0.0);

}  // namespace tessera::coordinator
