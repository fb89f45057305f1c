#include "launch/heap_retention.hpp"

#include <malloc.h>

namespace tessera::launch {

bool retain_freed_heap() {
  // The mapping threshold first: either call turns off glibc's dynamic adjustment, which would
  // otherwise have raised it towards the sizes actually freed.
  const bool mapping = mallopt(M_MMAP_THRESHOLD, static_cast<int>(kOwnMappingBytes)) == 1;
  const bool trim = mallopt(M_TRIM_THRESHOLD, static_cast<int>(kRetainedHeapBytes)) == 1;
  return mapping && trim;
}

bool release_freed_heap() {
  // mallinfo2's free bytes also count pages an earlier trim already handed back, so this can
  // trim when less is resident; it never keeps more than the bound.
  if (mallinfo2().fordblks < kRetainedHeapBytes) return false;
  malloc_trim(0);
  return true;
}

}  // namespace tessera::launch
