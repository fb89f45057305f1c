#pragma once
// What a launch run leaves behind and how it goes: its temporary folder, and the Fast DDS
// shared-memory files of killed processes (transport/fastdds/shm_leftovers.hpp).

#include <set>
#include <string>

namespace tessera::launch {

/// The run's folder of logs, summaries and generated files: by default a temporary one
/// (/tmp/tessera-launch-XXXXXX) created by the constructor (std::runtime_error when it cannot be)
/// and removed with everything in it by the destructor; with `keep` non-empty that folder,
/// created when missing and left in place (`tessera launch --keep-logs DIR`).
class WorkDir {
 public:
  explicit WorkDir(const std::string& keep = "");
  ~WorkDir();
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool keep_ = false;
};

/// Removes the shared-memory files of dead processes of `domain` (and the listed dead segments)
/// and says so on stderr; `when` completes the sentence ("before the run", ...).
void remove_dead_files_of(int domain, std::set<std::string> segments, const char* when);

}  // namespace tessera::launch
