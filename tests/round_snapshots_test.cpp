// When an agent takes round snapshots (core/runtime/checkpoint_keeper.hpp, snapshots_needed): a
// snapshot copies every block matrix each round (the trace shares its older records,
// distributed/round_history.hpp), so only runs where something reads them (rollback for a
// rejoin, a restart, checkpoint files, replicas) take them. That the iterates are unchanged either
// way is DdsSolve.*'s job; that rejoin, checkpoints and replicas still work is DdsRejoin.* /
// DdsLoss.*'s.

#include <gtest/gtest.h>

#include "runtime/checkpoint_keeper.hpp"

namespace tessera::agent {
namespace {

TEST(RoundSnapshots, NoneWhenNothingReadsThem) {
  EXPECT_FALSE(snapshots_needed(SnapshotReaders{}));
}

TEST(RoundSnapshots, EachReaderAloneNeedsThem) {
  SnapshotReaders r;
  r.rejoin = true;
  EXPECT_TRUE(snapshots_needed(r));
  r = SnapshotReaders{};
  r.restarted = true;
  EXPECT_TRUE(snapshots_needed(r));
  r = SnapshotReaders{};
  r.checkpoint_files = true;
  EXPECT_TRUE(snapshots_needed(r));
  r = SnapshotReaders{};
  r.replicas = true;
  EXPECT_TRUE(snapshots_needed(r));
}

}  // namespace
}  // namespace tessera::agent
