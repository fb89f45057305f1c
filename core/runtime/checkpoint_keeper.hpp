#pragma once
// An agent's recovery memory: the round snapshots it may be asked to roll back to (kept in
// memory for the last few rounds, whether or not it writes files) and, with a checkpoint
// folder, its checkpoint file rewritten every `every` rounds. Fed by the round loop at every
// consistent point (RoundProtocol's round observer).

#include <chrono>
#include <cstdint>
#include <deque>
#include <string>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

struct CheckpointOptions {
  std::string dir;  ///< Folder of the checkpoint file; "" = keep snapshots in memory only.
  int every = 1;    ///< Write the file every this many rounds (>= 1).
  /// Throws InputError naming the bad field.
  void validate() const;
};

struct CheckpointStats {
  std::uint64_t writes = 0;
  double write_s = 0.0;          ///< Wall time spent writing files (encode + write + fsync).
  std::uint64_t last_bytes = 0;  ///< Size of the last file payload.
  int last_round = -1;           ///< Round of the newest snapshot in the file.
};

/// What may read an agent's round snapshots in this run.
struct SnapshotReaders {
  bool rejoin = false;            ///< The coordinator may order a rollback (rejoin window).
  bool restarted = false;         ///< This agent resumed from its checkpoint file.
  bool checkpoint_files = false;  ///< --checkpoint-dir: the file is rewritten from them.
  bool replicas = false;          ///< Block replication sends the block of snapshot rounds.
};

/// True when some reader above is present. A snapshot copies every block matrix of the
/// protocol and its whole round trace, every round (kitti_02, N = 5: about a third of an
/// agent's CPU per round, none of which the in-process engine pays), so the round loop takes
/// none when nothing reads them; a rollback order then cannot arrive (only the coordinator's
/// rejoin arbiter sends one).
bool snapshots_needed(const SnapshotReaders& r);

class CheckpointKeeper {
 public:
  /// `local` must outlive the keeper (its data goes into every file).
  CheckpointKeeper(std::string run_id, const AgentLocalData& local, CheckpointOptions options);

  /// After a restart: the snapshots found in the checkpoint file (kept, so a later rollback
  /// to them still works).
  void adopt(const std::vector<ProtocolSnapshot>& from_file);
  /// A consistent point: remember it, and write the file when the round is due. A round seen
  /// again after a rollback replaces the earlier one (they are identical).
  void on_round(const ProtocolSnapshot& s);
  /// The snapshot of `round`, or null when it is no longer (or was never) kept.
  const ProtocolSnapshot* find(int round) const;
  /// Oldest and newest rounds held in memory ("" when none), for error messages.
  std::string held_rounds() const;
  const CheckpointStats& stats() const { return stats_; }
  std::string path() const;

 private:
  void write_file();
  std::string run_id_;
  const AgentLocalData& local_;
  CheckpointOptions opt_;
  std::size_t keep_;                       // rounds kept in memory
  std::deque<ProtocolSnapshot> memory_;    // consecutive rounds, oldest first
  std::vector<ProtocolSnapshot> in_file_;  // the last two checkpoint rounds
  CheckpointStats stats_;
};

}  // namespace tessera::agent
