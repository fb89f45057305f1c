// The agent's malloc settings (launch/heap_retention.hpp): freed memory at the top of the heap
// stays in the process instead of being trimmed and faulted back in by the next round. Each
// case runs in a forked child, since the settings are process-wide.
#include "launch/heap_retention.hpp"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "runtime/phase_memory.hpp"

namespace {

constexpr std::size_t kBlock = 96 * 1024;  // below glibc's initial mapping threshold: heap
constexpr int kBlocks = 40;                // ~3.8 MB, far above the default trim threshold

// Runs `body` in a forked child (the malloc settings are process-wide) and returns its result
// as the child's exit code, or -1 when the child could not run or did not exit.
template <class Body>
int exit_code_in_child(Body body) {
  const pid_t pid = fork();
  if (pid == 0) _exit(body());
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// In a child: optionally retain, grow the heap by kBlocks blocks, free them from the top down,
// and report through the exit code whether the freed top (keepcost) is still in the process.
int freed_top_kept_in_child(bool retain) {
  return exit_code_in_child([retain] {
    if (retain && !tessera::launch::retain_freed_heap()) return 3;
    std::vector<void*> blocks;
    blocks.reserve(kBlocks);
    for (int i = 0; i < kBlocks; ++i) {
      blocks.push_back(std::malloc(kBlock));
      if (!blocks.back()) return 4;
      std::memset(blocks.back(), 1, kBlock);  // touched: these pages are really in the process
    }
    for (int i = kBlocks - 1; i >= 0; --i) std::free(blocks[static_cast<std::size_t>(i)]);
    const struct mallinfo2 info = mallinfo2();
    return info.keepcost >= (kBlocks - 2) * kBlock ? 0 : 1;
  });
}

// In a child: retain, fill `blocks` blocks of `block` bytes (touched) below one more that
// pins them inside the heap (no trim at the top can take them), free them, then release.
// Exit code: 0 released and the resident memory fell by at least half of what was freed, 1
// kept and resident memory within 1 MB of before, 2 anything else; 3-5 set-up failures.
int release_in_child(std::size_t block, int blocks) {
  return exit_code_in_child([block, blocks] {
    if (!tessera::launch::retain_freed_heap()) return 3;
    std::vector<void*> filled;
    filled.reserve(static_cast<std::size_t>(blocks));
    for (int i = 0; i < blocks; ++i) {
      filled.push_back(std::malloc(block));
      if (!filled.back()) return 4;
      std::memset(filled.back(), 1, block);
    }
    // The pin: one more block of the same size, taken from the heap's top after the others
    // (a small one could come from a free chunk further down and pin nothing).
    void* pin = std::malloc(block);
    if (!pin) return 4;
    for (void* b : filled) std::free(b);
    const std::uint64_t before = tessera::agent::sample_phase_memory().rss;
    if (before == 0) return 5;
    const bool released = tessera::launch::release_freed_heap();
    const std::uint64_t after = tessera::agent::sample_phase_memory().rss;
    const std::uint64_t freed = block * static_cast<std::uint64_t>(blocks);
    const std::uint64_t slack = std::uint64_t{1} << 20;
    if (released && before > after && before - after >= freed / 2) return 0;
    if (!released && after + slack >= before && after <= before + slack) return 1;
    return 2;
  });
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

TEST(HeapRetention, AReleaseKeepsLessFreedHeapThanTheRetainedBound) {
  // ~3.8 MB freed inside the heap: handing it back would only make the next phase fault it in.
  EXPECT_EQ(release_in_child(kBlock, kBlocks), 1)
      << "0: trimmed, 2: resident memory moved, 3-5: set-up";
}

TEST(HeapRetention, AReleaseHandsBackMoreFreedHeapThanTheRetainedBound) {
  // 80 blocks of 1 MB (each below the own-mapping size, so on the heap): 80 MB > 64 MB.
  static_assert(80 * (std::size_t{1} << 20) > tessera::launch::kRetainedHeapBytes);
  static_assert((std::size_t{1} << 20) < tessera::launch::kOwnMappingBytes);
  EXPECT_EQ(release_in_child(std::size_t{1} << 20, 80), 0)
      << "1: kept, 2: released but resident memory did not fall, 3-5: set-up";
}
