// An agent's memory line at a phase (core/runtime/phase_memory.hpp).

#include "runtime/phase_memory.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace tessera::test {
namespace {

TEST(PhaseMemory, ABlockAllocatedAndTouchedShowsInTheHeapAndTheResidentSet) {
  const agent::PhaseMemory before = agent::sample_phase_memory();
  ASSERT_GT(before.rss, 0u);
  ASSERT_GE(before.hwm, before.rss);
  constexpr std::size_t kBytes = std::size_t{64} << 20;
  std::unique_ptr<char[]> block(new char[kBytes]);
  std::memset(block.get(), 1, kBytes);  // resident, not only reserved
  const agent::PhaseMemory during = agent::sample_phase_memory();
  EXPECT_GE(during.heap_in_use, before.heap_in_use + kBytes);
  EXPECT_GE(during.heap_mapped, kBytes);  // a block this large is mapped on its own
  EXPECT_GE(during.rss, before.rss + kBytes / 2);
  block.reset();
  const agent::PhaseMemory after = agent::sample_phase_memory();
  EXPECT_LT(after.heap_in_use, during.heap_in_use);
  EXPECT_GE(after.hwm, before.rss + kBytes / 2);  // the peak stays
}

TEST(PhaseMemory, TheLineNamesThePhaseAndEveryFigureInMegabytes) {
  agent::PhaseMemory m;
  m.rss = std::uint64_t{300} << 20;
  m.hwm = std::uint64_t{310} << 20;
  m.heap_in_use = std::uint64_t{200} << 20;
  m.heap_mapped = std::uint64_t{150} << 20;
  m.heap_free = std::uint64_t{40} << 20;
  EXPECT_EQ(agent::phase_memory_line("block set-up", m),
            "memory after block set-up: rss 300.0 MB, hwm 310.0 MB, heap in use 200.0 MB "
            "(150.0 MB own maps), heap free 40.0 MB");
}

}  // namespace
}  // namespace tessera::test
