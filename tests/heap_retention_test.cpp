// The agent's malloc settings (launch/heap_retention.hpp): freed memory at the top of the heap
// stays in the process instead of being trimmed and faulted back in by the next round. Each
// case runs in a forked child, since the settings are process-wide.
#include "launch/heap_retention.hpp"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace {

constexpr std::size_t kBlock = 96 * 1024;  // below glibc's initial mapping threshold: heap
constexpr int kBlocks = 40;                // ~3.8 MB, far above the default trim threshold

// In a child: optionally retain, grow the heap by kBlocks blocks, free them from the top down,
// and report through the exit code whether the freed top (keepcost) is still in the process.
int freed_top_kept_in_child(bool retain) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (retain && !tessera::launch::retain_freed_heap()) _exit(3);
    std::vector<void*> blocks;
    blocks.reserve(kBlocks);
    for (int i = 0; i < kBlocks; ++i) {
      blocks.push_back(std::malloc(kBlock));
      if (!blocks.back()) _exit(4);
      std::memset(blocks.back(), 1, kBlock);  // touched: these pages are really in the process
    }
    for (int i = kBlocks - 1; i >= 0; --i) std::free(blocks[static_cast<std::size_t>(i)]);
    const struct mallinfo2 info = mallinfo2();
    _exit(info.keepcost >= (kBlocks - 2) * kBlock ? 0 : 1);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

}  // namespace

TEST(HeapRetention, FreedHeapTopStaysInTheProcess) {
  EXPECT_EQ(freed_top_kept_in_child(true), 0) << "1: trimmed, 3: setting refused, 4: no memory";
}

TEST(HeapRetention, WithoutItGlibcTrimsTheSameHeap) {
  // The control: the same pattern under glibc's defaults hands the top back, which is what
  // cost the agents a fault per page and round.
  EXPECT_EQ(freed_top_kept_in_child(false), 1);
}
