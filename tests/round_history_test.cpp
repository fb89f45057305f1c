// RoundHistory (core/include/tessera/distributed/round_history.hpp): the protocol's trace, which
// snapshots copy every round. Copies share full chunks, yet behave as independent values: records
// read back in order across chunk boundaries, and changing or growing one copy never shows in
// another (a snapshot keeps the restart flag and length it was taken with).

#include <gtest/gtest.h>

#include <tessera/distributed/round_history.hpp>

namespace tessera {
namespace {

RoundRecord record(int k) {
  RoundRecord r;
  r.round = k;
  r.cost = 1000.0 - k;
  r.grad_norm = 1.0 / (k + 1);
  r.selected = {k % 3, k % 5};
  r.elapsed_s = 0.01 * k;
  return r;
}

void expect_rounds(const RoundHistory& h, int n) {
  ASSERT_EQ(h.size(), static_cast<std::size_t>(n));
  EXPECT_EQ(h.empty(), n == 0);
  const std::vector<RoundRecord> all = h.to_vector();
  ASSERT_EQ(all.size(), static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    EXPECT_EQ(h[i].round, k);
    EXPECT_EQ(h[i].cost, 1000.0 - k);
    EXPECT_EQ(h[i].selected, record(k).selected);
    EXPECT_EQ(all[i].round, k);
    EXPECT_EQ(all[i].selected, record(k).selected);
  }
  if (n > 0) {
    EXPECT_EQ(h.back().round, n - 1);
  }
}

TEST(RoundHistory, RecordsReadBackInOrderAcrossChunks) {
  RoundHistory h;
  expect_rounds(h, 0);
  const int n = 3 * static_cast<int>(RoundHistory::kChunk) + 5;
  for (int k = 0; k < n; ++k) {
    h.push_back(record(k));
    expect_rounds(h, k + 1);
  }
}

TEST(RoundHistory, CopiesAreIndependentValues) {
  const int chunk = static_cast<int>(RoundHistory::kChunk);
  RoundHistory h;
  std::vector<RoundHistory> snapshots;  // one per length 0..3 chunks, taken as a run would
  for (int k = 0; k < 3 * chunk; ++k) {
    snapshots.push_back(h);
    h.push_back(record(k));
    if (k % 7 == 0) h.back().restart = true;  // set after the record was added, as a restart is
  }
  // The last record of a copy changes in that copy only, on a chunk boundary or not.
  for (int n : {chunk, chunk + 1, 2 * chunk}) {
    RoundHistory copy = snapshots[static_cast<std::size_t>(n)];
    copy.back().restart = !copy.back().restart;
    copy.push_back(record(999));
    EXPECT_EQ(h[static_cast<std::size_t>(n - 1)].restart, (n - 1) % 7 == 0);
    EXPECT_EQ(snapshots[static_cast<std::size_t>(n)].back().restart, (n - 1) % 7 == 0);
    EXPECT_EQ(copy[static_cast<std::size_t>(n)].round, 999);
    EXPECT_EQ(snapshots[static_cast<std::size_t>(n)].size(), static_cast<std::size_t>(n));
  }
  for (std::size_t n = 0; n < snapshots.size(); ++n) {
    expect_rounds(snapshots[n], static_cast<int>(n));
    for (std::size_t k = 0; k < n; ++k) EXPECT_EQ(snapshots[n][k].restart, k % 7 == 0) << n;
  }
  // A copy that grows past a chunk boundary does not disturb the original's records.
  RoundHistory grown = snapshots[static_cast<std::size_t>(chunk - 1)];
  for (int k = 0; k < chunk + 2; ++k) grown.push_back(record(500 + k));
  expect_rounds(h, 3 * chunk);
  EXPECT_EQ(grown.size(), static_cast<std::size_t>(2 * chunk + 1));
  EXPECT_EQ(grown[static_cast<std::size_t>(chunk)].round, 501);
}

}  // namespace
}  // namespace tessera
