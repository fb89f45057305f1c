#pragma once
// One line of an agent's memory at a phase of its run (--verbose): what the kernel holds for the
// process (VmRSS, VmHWM) beside what malloc has handed out (in use) and kept (free), so that a
// growth can be told apart as live data, retained free heap, or pages that are not malloc's
// (Fast DDS's shared-memory segments, thread stacks, the fork server's shared pages).

#include <cstdint>
#include <string>

namespace tessera::agent {

/// The process's memory now, in bytes; a field is 0 when the system does not report it.
struct PhaseMemory {
  std::uint64_t rss = 0;          ///< VmRSS: resident now (shared pages counted in full).
  std::uint64_t hwm = 0;          ///< VmHWM: the peak of VmRSS so far.
  std::uint64_t heap_in_use = 0;  ///< malloc's live bytes, every arena and its own mappings.
  std::uint64_t heap_mapped = 0;  ///< Of those, blocks mapped on their own (large blocks).
  /// Freed bytes malloc keeps in its arenas; after malloc_trim their whole pages are handed
  /// back to the kernel but still counted here, so this bounds what is resident, it is not it.
  std::uint64_t heap_free = 0;
  std::uint64_t heap_arenas = 0;  ///< Bytes of the arenas (in use + free, without own maps).
};

/// Reads /proc/self/status and malloc's statistics (glibc's mallinfo2 sums every arena).
PhaseMemory sample_phase_memory();

/// "memory after PHASE: rss 123.4 MB, hwm 150.2 MB, heap in use 80.1 MB (20.0 MB own maps),
/// heap free 10.3 MB": what an agent logs at each phase.
std::string phase_memory_line(const std::string& phase, const PhaseMemory& m);

/// phase_memory_line(phase, sample_phase_memory()).
std::string phase_memory_line(const std::string& phase);

}  // namespace tessera::agent
