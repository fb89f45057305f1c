#include "launch/run_cleanup.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "transport/fastdds/shm_leftovers.hpp"

namespace tessera::launch {

WorkDir::WorkDir(const std::string& keep) {
  if (!keep.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(keep, ec);
    if (ec) throw std::runtime_error("launch: cannot create " + keep + ": " + ec.message());
    path_ = keep;
    keep_ = true;
    return;
  }
  char tmpl[] = "/tmp/tessera-launch-XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error("launch: cannot create a temporary folder");
  path_ = tmpl;
}

// In process (no `sh -c rm -rf`: two more process starts at the end of every run).
WorkDir::~WorkDir() {
  if (keep_) return;
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  if (ec)
    std::fprintf(stderr, "tessera launch: could not remove %s: %s\n", path_.c_str(),
                 ec.message().c_str());
}

void remove_dead_files_of(int domain, std::set<std::string> segments, const char* when) {
  transport::ShmCleanupOptions shm;
  shm.domain = domain;
  shm.segments = std::move(segments);
  const transport::ShmCleanupResult r = transport::remove_dead_shm_files(shm);
  if (!r.removed.empty())
    std::fprintf(stderr,
                 "tessera launch: removed %zu shared-memory files of dead processes of domain %d "
                 "from /dev/shm %s\n",
                 r.removed.size(), domain, when);
}

}  // namespace tessera::launch
