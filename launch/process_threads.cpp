#include "launch/process_threads.hpp"

#include <dirent.h>

#include <cstdlib>

namespace tessera::launch {

int change_every_thread(const std::function<bool(pid_t)>& change) {
  int changed = 0;
  for (int pass = 0; pass < 2; ++pass) {
    DIR* dir = opendir("/proc/self/task");
    if (!dir) return changed;
    while (dirent* e = readdir(dir)) {
      if (e->d_name[0] == '.') continue;
      if (change(static_cast<pid_t>(std::atol(e->d_name)))) ++changed;
    }
    closedir(dir);
  }
  return changed;
}

}  // namespace tessera::launch
