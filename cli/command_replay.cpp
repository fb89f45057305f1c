// `tessera replay`: runs tessera-replay beside this executable (cli/replay/), which holds the
// DDS writer: `tessera` itself never links Fast DDS.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "commands.hpp"

namespace tessera::cli {

int run_replay(const Args& args) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string exe = (ec ? std::filesystem::path(".") : self.parent_path()) / "tessera-replay";
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  execv(exe.c_str(), argv.data());
  throw InputError("replay needs " + exe + " (built with DDS): " + std::strerror(errno));
}

}  // namespace tessera::cli
