#include "runtime/preloaded_graph.hpp"

#include <memory>
#include <tessera/io/g2o_reader.hpp>
#include <utility>

#include "runtime/robot_file.hpp"

namespace tessera::agent {

namespace {

struct Preloaded {
  std::string path;
  PoseGraph graph;
};

// Never freed: in a forked agent, freeing would write to (and so copy) the pages it shares
// with the fork server and the other agents.
std::unique_ptr<Preloaded>& slot() {
  static std::unique_ptr<Preloaded> preloaded;
  return preloaded;
}

}  // namespace

void preload_graph(const std::string& path) noexcept {
  slot().reset();
  try {
    if (is_robot_file(path)) return;
    auto p = std::make_unique<Preloaded>();
    p->graph = read_g2o(path);
    p->path = path;
    slot() = std::move(p);
  } catch (...) {
    // Any failure (unreadable, malformed, out of memory): nothing kept; each agent reads the
    // file itself and names the problem.
  }
}

const PoseGraph* preloaded_graph(const std::string& path) {
  const auto& p = slot();
  return p && p->path == path ? &p->graph : nullptr;
}

}  // namespace tessera::agent
