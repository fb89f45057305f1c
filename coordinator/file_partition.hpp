#pragma once
// The partition of the whole graph file, computed while the agents start up.
//
// Without it the coordinator can partition only once every agent has announced its part of
// the structure, so the agents' process start, participant creation and discovery come
// before the (single-threaded) partition on the critical path. `tessera launch` runs every
// process on one host and knows the file, so it passes it (`--graph FILE`): the coordinator
// reads the file's structure and partitions it on a thread started before its participant
// (FilePartitionJob), while it creates the participant and the agents start and announce
// themselves. The announcements are still gathered and checked
// as before, and the early partition is used only when the announced structure is exactly
// the file's (same poses, same endpoints in the same order): then it is the partition the
// announced structure would get (the partitioner is deterministic for a structure, preset
// and seed). Otherwise the announced structure is partitioned as without the file.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coordinator/run_structure.hpp"
#include "runtime/partition_step.hpp"

namespace tessera::coordinator {

struct FilePartition {
  std::size_t num_poses = 0;
  std::vector<std::uint32_t> edge_i, edge_j;  ///< The file's measurements' endpoints, in order.
  PartitionStepResult part;

  /// True when `rs` (the announced structure) is the file's: same number of poses and the
  /// same endpoints in the same order.
  bool fits(const RunStructure& rs) const;
};

/// Reads the g2o file's structure and partitions it as partition_for_agents would. Returns
/// nothing, with the reason in `why`, when the file cannot be read or partitioned: the run
/// then partitions the announcements (the agents, which read the same file, report their
/// own error if the file is bad).
std::optional<FilePartition> partition_graph_file(const std::string& path, std::uint32_t num_agents,
                                                  const std::string& preset, std::uint64_t seed,
                                                  std::string* why, double time_limit_s = 0.0);

/// partition_graph_file on a thread of its own, started at once, its nice moved by
/// `nice_offset` (-20..0) from the process's where the kernel allows it (partition_priority.hpp;
/// the result's `part.thread_nice` says by how much it was). The thread is detached: a process that
/// fails before taking the result exits (transport::exit_process) without waiting for it.
class FilePartitionJob {
 public:
  FilePartitionJob(std::string path, std::uint32_t num_agents, std::string preset,
                   std::uint64_t seed, double time_limit_s = 0.0, int nice_offset = 0);
  /// True once the result is there; waits at most `wait` for it.
  bool ready(std::chrono::milliseconds wait) const;
  /// Waits for the result (local work with no timeout, like the partition of the
  /// announcements) and hands it over; call once. `started` / `ended`: when the thread began
  /// and finished (for the run's timeline).
  std::optional<FilePartition> take(std::string* why,
                                    std::chrono::steady_clock::time_point* started,
                                    std::chrono::steady_clock::time_point* ended);

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace tessera::coordinator
