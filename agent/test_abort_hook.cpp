#include "agent/test_abort_hook.hpp"

#include <signal.h>

#include <cstdlib>
#include <iostream>
#include <map>
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

bool test_kill_armed() {
  return std::getenv("TESSERA_TEST_AGENT_KILL") != nullptr;
}

void test_kill_point(ProgressStage stage, std::uint32_t id) {
  const char* env = std::getenv("TESSERA_TEST_AGENT_KILL");
  if (!env) return;
  std::string spec = env;
  const std::size_t colon = spec.find(':');
  if (colon != std::string::npos) {
    if (spec.substr(colon + 1) != std::to_string(id)) return;
    spec = spec.substr(0, colon);
  }
  unsigned long at = 1;
  const std::size_t sign = spec.find('@');
  if (sign != std::string::npos) {
    at = std::stoul(spec.substr(sign + 1));
    spec = spec.substr(0, sign);
  }
  const char* name = stage == ProgressStage::kRefinement    ? "refinement"
                     : stage == ProgressStage::kCertificate ? "certificate"
                                                            : "rounding";
  if (spec != name) return;
  static std::map<ProgressStage, unsigned long> seen;
  if (++seen[stage] != at) return;
  std::cerr << "tessera-agent[" << id << "]: TESSERA_TEST_AGENT_KILL: killed in the " << name
            << " (progress point " << at << ")" << std::endl;
  raise(SIGKILL);
}

}  // namespace tessera::agent
