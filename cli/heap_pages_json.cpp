#include "heap_pages_json.hpp"

#include "launch/heap_pages.hpp"

namespace tessera::cli {

void add_heap_pages(JsonObject& j) {
  const launch::HeapPagesChoice heap = launch::heap_pages_in_effect();
  j.add("heap_pages", heap.name());
  if (heap.fresh_page_us >= 0)
    j.add("fresh_page_us", heap.fresh_page_us);
  else
    j.add_null("fresh_page_us");
}

}  // namespace tessera::cli
