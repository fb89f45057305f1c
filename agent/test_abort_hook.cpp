#include "agent/test_abort_hook.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <thread>

namespace tessera::agent {

namespace {

// The part of a "VALUE[:ID]" spec before the colon, or nothing when the spec names another
// agent. The value may not contain a colon.
std::optional<std::string> spec_for(const char* env, std::uint32_t id) {
  const std::string spec = env;
  const std::size_t colon = spec.find(':');
  if (colon != std::string::npos && spec.substr(colon + 1) != std::to_string(id))
    return std::nullopt;
  return spec.substr(0, colon);
}

}  // namespace

void test_abort_point(TestAbortPoint at, std::uint32_t id) {
  const char* env = std::getenv("TESSERA_TEST_AGENT_ABORT");
  if (!env) return;
  const std::optional<std::string> when = spec_for(env, id);
  if (!when) return;
  const char* name = at == TestAbortPoint::kBeforeResult ? "before-result" : "after-finished";
  if (*when != name) return;
  std::cerr << "tessera-agent[" << id << "]: TESSERA_TEST_AGENT_ABORT: aborting " << name
            << std::endl;
  // From another thread, like Fast DDS's lease check in its event thread.
  std::thread([] { std::abort(); }).join();
}

void test_hold_point(std::uint32_t id) {
  const char* env = std::getenv("TESSERA_TEST_AGENT_HOLD");
  if (!env) return;
  const std::optional<std::string> path = spec_for(env, id);
  if (!path) return;
  std::cerr << "tessera-agent[" << id << "]: TESSERA_TEST_AGENT_HOLD: holding the result until "
            << *path << " exists" << std::endl;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (access(path->c_str(), F_OK) != 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

bool test_kill_armed() {
  return std::getenv("TESSERA_TEST_AGENT_KILL") != nullptr;
}

void test_kill_point(ProgressStage stage, std::uint32_t id) {
  const char* env = std::getenv("TESSERA_TEST_AGENT_KILL");
  if (!env) return;
  const std::optional<std::string> mine = spec_for(env, id);
  if (!mine) return;
  std::string spec = *mine;
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
