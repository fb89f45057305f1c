#pragma once
// An agent keeps the heap memory it frees instead of handing it back to the kernel at once.
//
// A round allocates and frees the same temporaries (sparse-dense products, the trust region's
// work matrices); with glibc's default, dynamic thresholds, freeing them often shrank the heap
// (trim) and the next round faulted the same pages back in: ~100k minor faults in a kitti_02
// run of 5 agents against ~6k in the in-process engine, ~10 us of CPU each on the virtual
// machines measured, i.e. ~1 CPU-s of a 5-6 CPU-s run (docs/dds-runtime.md, "The agents'
// heap"). This removes those faults, for agents started by hand too.

#include <cstddef>

namespace tessera::launch {

/// Freed memory at the top of the heap is returned to the kernel only beyond this many bytes.
inline constexpr std::size_t kRetainedHeapBytes = std::size_t{64} << 20;
/// Blocks of at least this many bytes are mapped on their own (and unmapped when freed):
/// glibc's own ceiling for its dynamic threshold, fixed here because setting the trim
/// threshold turns the dynamic one off.
inline constexpr std::size_t kOwnMappingBytes = std::size_t{32} << 20;

/// Sets the process's malloc to keep up to kRetainedHeapBytes of freed heap and to map blocks
/// of kOwnMappingBytes or more separately. Process-wide; call once, early. Returns false (and
/// changes nothing that matters for correctness) when the C library refuses a setting.
bool retain_freed_heap();

/// Hands every whole free page of the heap back to the kernel now (malloc_trim) when malloc
/// holds at least kRetainedHeapBytes of free heap: called where a set-up phase's transients (the
/// file's text, the initialisation's factorization) were just freed, so the rounds do not run on
/// top of them. In a run of many agents on one host those kept pages add up. Below the bound the
/// pages stay, as they do at the heap's top: trimming them cost each agent a few madvise calls
/// and the next phase a fault per page it touched again. Returns whether it trimmed.
bool release_freed_heap();

}  // namespace tessera::launch
