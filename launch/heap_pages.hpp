#pragma once
// Which page size a run's heaps use, chosen from what this host charges for a fresh page: the
// one seam for that host quirk. `tessera solve` and `tessera launch` call enter_heap_pages()
// first; launch's processes inherit the choice through their environment.
//
// Why: a process's first touch of a 4 KB page costs the kernel a fault. On most virtual machines
// measured that is 1.5-3.2 us, but on some (shadow page tables) 11-22 us, so a city10000 launch's
// ~57 k faults cost ~1 CPU-s there. glibc can put the heap in transparent 2 MB pages
// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1), a fault per 2 MB; but where the host takes back freed
// memory, a 2 MB page first touched after a pause costs 1.5-3 ms per MB (6-12 us per 4 KB of it),
// more than 4 KB pages on a fast-fault host (docs/dds-runtime.md, "Heaps in 4 KB pages"). So
// the heaps are huge only where the probe says a 4 KB page costs kHugeFromFreshPageUs or more.

#include <string>

namespace tessera::launch {

/// --heap-pages: `auto` (probe this host), `4k` (glibc's default) or `2m` (huge-page heaps).
enum class HeapPages { kAuto, kSmall, kHuge };

/// Parses "auto", "4k" or "2m"; throws InputError naming `flag` otherwise.
HeapPages parse_heap_pages(const std::string& value, const std::string& flag);

/// From this first-touch cost of a fresh 4 KB page (microseconds) up, `auto` takes 2 MB pages:
/// above the 6-12 us per 4 KB that a 2 MB page first touched after a pause costs, below the
/// 11-22 us of the slow-fault hosts measured, above the 1.5-3.2 us of the others.
inline constexpr double kHugeFromFreshPageUs = 8.0;

/// What a process's heap runs on, and why.
struct HeapPagesChoice {
  bool huge = false;          ///< glibc.malloc.hugetlb=1 (2 MB pages) is, or is to be, in effect
  double fresh_page_us = -1;  ///< the probe's cost of a fresh 4 KB page; -1: not measured
  std::string reason;         ///< one line: the flag, the user's GLIBC_TUNABLES, the probe
  std::string name() const { return huge ? "2m" : "4k"; }
};

/// The decision without side effects. `tunables`: GLIBC_TUNABLES as the process has it (a
/// user's glibc.malloc.hugetlb there wins over `auto`); `thp`: the text of
/// /sys/kernel/mm/transparent_hugepage/enabled ("[never]" there: 2 MB pages cannot be had);
/// `fresh_page_us`: the probe, asked for only by `auto` when nothing above decides.
HeapPagesChoice decide_heap_pages(HeapPages mode, const std::string& tunables,
                                  const std::string& thp, double (*probe)());

/// Microseconds a first write to a fresh 4 KB anonymous page costs here: the fastest of 4
/// batches of 32 pages (a preempted batch does not count), ~3 ms in all on the slowest host
/// measured.
double fresh_page_cost_us();

/// Puts this process's heap on the page size `mode` selects. When that needs huge pages not yet
/// in effect, it re-executes the process (/proc/self/exe with its own command line) with
/// glibc.malloc.hugetlb=1 added to GLIBC_TUNABLES and the choice recorded in the environment, so
/// it returns only in the process that runs on the chosen heap (or when the re-execution
/// failed: then 4 KB pages, said in the reason). Call it first, before the process allocates
/// what it will use. Children started later inherit the environment, and so the choice.
HeapPagesChoice enter_heap_pages(HeapPages mode);

/// The choice in effect in this process, from its environment (what enter_heap_pages() of this
/// process or of its parent recorded; else what GLIBC_TUNABLES says). For run summaries.
HeapPagesChoice heap_pages_in_effect();

}  // namespace tessera::launch
