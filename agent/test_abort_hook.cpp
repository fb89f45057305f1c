#include "agent/test_abort_hook.hpp"

#include <cstdlib>
#include <iostream>
#include <string>
#include <thread>

namespace tessera::agent {

void test_abort_point(TestAbortPoint at, std::uint32_t id) {
  const char* env = std::getenv("TESSERA_TEST_AGENT_ABORT");
  if (!env) return;
  const std::string spec = env;
  const std::size_t colon = spec.find(':');
  const std::string when = spec.substr(0, colon);
  if (colon != std::string::npos && spec.substr(colon + 1) != std::to_string(id)) return;
  const char* name = at == TestAbortPoint::kBeforeResult ? "before-result" : "after-finished";
  if (when != name) return;
  std::cerr << "tessera-agent[" << id << "]: TESSERA_TEST_AGENT_ABORT: aborting " << name
            << std::endl;
  // From another thread, like Fast DDS's lease check in its event thread.
  std::thread([] { std::abort(); }).join();
}

}  // namespace tessera::agent
