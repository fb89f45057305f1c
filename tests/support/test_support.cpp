#include "test_support.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <vector>

namespace tessera::test {

std::string shared_dir() {
  namespace fs = std::filesystem;
  const char* env = std::getenv("TESSERA_SHARED_DIR");
  fs::path p = env ? fs::path(env) : fs::path(TESSERA_SHARED_DIR);
  if (fs::is_directory(p / "datasets")) return fs::weakly_canonical(p).string();
  return "";
}

namespace {

// The directories temp_dir() made during the running test. A passed test's are removed when it
// ends (a suite run makes ~800 of them, some with whole runs' logs); a failed test's stay for
// the post-mortem, and TESSERA_KEEP_TEST_DIRS=1 keeps every one.
class TempDirCleanup : public ::testing::EmptyTestEventListener {
 public:
  void add(const std::string& dir) {
    std::lock_guard<std::mutex> lock(mutex_);
    dirs_.push_back(dir);
  }
  void OnTestEnd(const ::testing::TestInfo& info) override {
    std::vector<std::string> dirs;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      dirs.swap(dirs_);
    }
    const char* keep = std::getenv("TESSERA_KEEP_TEST_DIRS");
    if (!info.result()->Passed() || (keep && std::string(keep) == "1")) return;
    for (const std::string& dir : dirs) {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  }

 private:
  std::mutex mutex_;
  std::vector<std::string> dirs_;
};

// Registered on first use; the listener list owns it.
TempDirCleanup& temp_dir_cleanup() {
  static TempDirCleanup* cleanup = [] {
    auto* listener = new TempDirCleanup;
    ::testing::UnitTest::GetInstance()->listeners().Append(listener);
    return listener;
  }();
  return *cleanup;
}

}  // namespace

std::string temp_dir() {
  namespace fs = std::filesystem;
  std::random_device rd;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string stem = info ? std::string(info->test_suite_name()) + "_" + info->name() : "tessera";
  fs::path p = fs::temp_directory_path() / ("tessera_test_" + stem + "_" + std::to_string(rd()));
  fs::create_directories(p);
  // Only a running test's directory: one made outside a test may be shared by several.
  if (info) temp_dir_cleanup().add(p.string());
  return p.string();
}

std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  std::string path = dir + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

int run_command(const std::string& command, std::string* output) {
  std::string full = command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf{};
  std::string out;
  std::size_t got;
  while ((got = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), got);
  int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string bin(const std::string& name) {
  return std::string(TESSERA_BIN_DIR) + "/" + name;
}

}  // namespace tessera::test
