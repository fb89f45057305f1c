#include "launch/process_tuning.hpp"

#include "launch/heap_retention.hpp"
#include "launch/serial_openmp.hpp"
#include "launch/startup_batch.hpp"

namespace tessera::launch {

void begin_agent_process() {
  retain_freed_heap();
  serial_openmp();
}

std::string end_agent_startup() {
  const std::string unbatched = restore_startup_batch();
  return unbatched.empty() ? "" : "start-up batch: " + unbatched;
}

}  // namespace tessera::launch
