// launch() of the public API (<tessera/dds/launch.hpp>): the options become `tessera launch`'s
// command line, so a program and the command parse, check and run the same way.

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <tessera/dds/launch.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "io/number_text.hpp"
#include "launch/launch.hpp"

namespace tessera::dds {

namespace {

// Whether `dir` holds the executables launch starts.
bool holds_executables(const std::string& dir) {
  return access((dir + "/tessera-agent").c_str(), X_OK) == 0 &&
         access((dir + "/tessera-coordinator").c_str(), X_OK) == 0;
}

// The folder of the executables (LaunchOptions::bin_dir in <tessera/dds/launch.hpp>): `bin_dir`
// when given; else the first that holds them of the running program's folder (a build tree, or
// a program installed beside them), the bindir of the install prefix this library was
// configured for, and the folders on PATH (an installed package moved to another prefix whose
// bin/ is on PATH). Throws InputError naming the folders looked in.
std::string executables_dir(const std::string& bin_dir) {
  if (!bin_dir.empty()) return bin_dir;
  std::vector<std::string> candidates{launch::running_program_dir()};
#ifdef TESSERA_INSTALL_BINDIR
  candidates.push_back(TESSERA_INSTALL_BINDIR);
#endif
  for (const std::string& dir : candidates)
    if (holds_executables(dir)) return dir;
  if (const char* path = std::getenv("PATH")) {
    std::istringstream dirs(path);
    for (std::string dir; std::getline(dirs, dir, ':');)
      if (!dir.empty() && holds_executables(dir)) return dir;
  }
  std::string looked;
  for (const std::string& dir : candidates) looked += dir + ", ";
  throw InputError("launch: tessera-agent and tessera-coordinator not found in " + looked +
                   "or on PATH; set LaunchOptions::bin_dir (find_package(Tessera) sets "
                   "Tessera_BINDIR to the package's)");
}

}  // namespace

std::string LaunchResult::full_report() const {
  std::ostringstream out;
  out << "run " << run_id << ": "
      << (exit_code == 0     ? "done"
          : exit_code == 130 ? "interrupted"
                             : "failed");
  if (!failure.empty()) out << " (" << failure << ")";
  out << ", exit code " << exit_code << "\n";
  char wall[64];
  std::snprintf(wall, sizeof(wall), "%.2f", wall_s);
  out << "wall time " << wall << " s\n";
  for (const auto& p : lost) out << "lost during the run: " << p << "\n";
  for (const auto& n : notes) out << "note: " << n << "\n";
  out << "summary: " << (summary_json.empty() ? "none\n" : "\n" + summary_json);
  return out.str();
}

std::vector<std::string> LaunchOptions::argv() const {
  std::vector<std::string> a;
  if (!graph.empty()) a.push_back(graph);
  a.insert(a.end(),
           {"--agents", std::to_string(agents), "--algorithm", algorithm, "--partition", partition,
            "--grad-tol", exact_text(grad_tol), "--timeout", exact_text(timeout_s)});
  if (!certify) a.push_back("--no-certify");
  if (!json.empty()) a.insert(a.end(), {"--json", json});
  if (!out.empty()) a.insert(a.end(), {"--out", out});
  if (quiet) a.push_back("--quiet");
  const SessionOptions defaults;
  // launch makes a fresh run id per run unless one is given.
  if (session.run_id != defaults.run_id) a.insert(a.end(), {"--run-id", session.run_id});
  const std::vector<std::string> s = session.argv(false);
  a.insert(a.end(), s.begin() + 2, s.end());  // without the --run-id pair
  a.insert(a.end(), extra_args.begin(), extra_args.end());
  return a;
}

void LaunchOptions::validate() const {
  launch::parse_launch_options(argv());
}

LaunchResult launch(const LaunchOptions& options) {
  launch::LaunchOptions o = launch::parse_launch_options(options.argv());
  o.bin_dir = executables_dir(options.bin_dir);
  return launch::launch(std::move(o));
}

}  // namespace tessera::dds
