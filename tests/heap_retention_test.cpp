// The agent's malloc settings (launch/heap_retention.hpp): freed memory at the top of the heap
// stays in the process instead of being trimmed and faulted back in by the next round. Each
// case runs in a forked child, since the settings are process-wide.
#include "launch/heap_retention.hpp"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
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

// Resident bytes of this process (/proc/self/statm), or 0 when unreadable.
std::size_t resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  unsigned long size = 0, resident = 0;
  const int read = std::fscanf(f, "%lu %lu", &size, &resident);
  std::fclose(f);
  return read == 2 ? resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE)) : 0;
}

// In a child: retain, fill `blocks` blocks of `block` bytes (touched) below one more that
// pins them inside the heap (no trim at the top can take them), free them, then release.
// Exit code: 0 released and the resident memory fell by at least half of what was freed, 1
// kept and resident memory within 1 MB of before, 2 anything else; 3-5 set-up failures.
int release_in_child(std::size_t block, int blocks) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (!tessera::launch::retain_freed_heap()) _exit(3);
    std::vector<void*> filled;
    filled.reserve(static_cast<std::size_t>(blocks));
    for (int i = 0; i < blocks; ++i) {
      filled.push_back(std::malloc(block));
      if (!filled.back()) _exit(4);
      std::memset(filled.back(), 1, block);
    }
    // The pin: one more block of the same size, taken from the heap's top after the others
    // (a small one could come from a free chunk further down and pin nothing).
    void* pin = std::malloc(block);
    if (!pin) _exit(4);
    for (void* b : filled) std::free(b);
    const std::size_t before = resident_bytes();
    if (before == 0) _exit(5);
    const bool released = tessera::launch::release_freed_heap();
    const std::size_t after = resident_bytes();
    const std::size_t freed = block * static_cast<std::size_t>(blocks);
    if (released && before > after && before - after >= freed / 2) _exit(0);
    if (!released && after + (std::size_t{1} << 20) >= before && after <= before + (1u << 20))
      _exit(1);
    _exit(2);
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
