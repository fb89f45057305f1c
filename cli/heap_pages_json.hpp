#pragma once
// The heaps' page size in a run summary (launch/heap_pages.hpp): shared by `tessera solve` and
// the coordinator's summary of a launch.

#include "json_writer.hpp"

namespace tessera::cli {

/// Adds "heap_pages" ("4k" or "2m", as this process runs) and "fresh_page_us" (the probe's
/// cost of a fresh 4 KB page, null when none was measured).
void add_heap_pages(JsonObject& j);

}  // namespace tessera::cli
