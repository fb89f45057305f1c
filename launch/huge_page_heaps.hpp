#pragma once
// Launch's processes (the fork server and what it forks, or the exec'ed coordinator and
// agents) allocate their heaps in transparent huge pages where the kernel allows it (glibc's
// `glibc.malloc.hugetlb=1` tunable: malloc madvises its heap MADV_HUGEPAGE). A freshly forked
// agent touches ~1000 new 4 KB pages before the coordinator's partition ends, and on the
// virtual machines measured a page fault costs ~10 us of CPU, spent while the partition wants
// both cores (docs/dds-runtime.md, "Start-up"). With huge pages the agents fault
// ~20-25 % less up to the assignment and ~35 % less over a CSAIL run.
//
// A tunable is read when a program starts, so it goes into launch's own environment before
// it starts any process; launch itself (already running) is unaffected. A user who set
// glibc.malloc.hugetlb in GLIBC_TUNABLES (e.g. =0 to turn this off) keeps that value.

#include <string>

namespace tessera::launch {

/// `tunables` (the value of GLIBC_TUNABLES, "" when unset) with glibc.malloc.hugetlb=1
/// added, unless it already names glibc.malloc.hugetlb (then unchanged).
std::string with_huge_page_heaps(const std::string& tunables);

/// Sets GLIBC_TUNABLES to with_huge_page_heaps(its current value) for the processes this one
/// starts from now on.
void request_huge_page_heaps();

}  // namespace tessera::launch
