// run_coordinator() of the public API (<tessera/dds/coordinator.hpp>): the options become
// tessera-coordinator's command line, so a hosted coordinator and the executable parse, check
// and run the same way.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <tessera/dds/coordinator.hpp>

#include "coordinator/coordinator_entry.hpp"
#include "coordinator/coordinator_options.hpp"
#include "io/number_text.hpp"

namespace tessera::dds {

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

std::vector<std::string> CoordinatorOptions::argv() const {
  std::vector<std::string> a = {
      "--agents",      std::to_string(agents),   "--partition", partition, "--algorithm", algorithm,
      "--run-timeout", exact_text(run_timeout_s)};
  const std::vector<std::string> s = session.argv();
  a.insert(a.end(), s.begin(), s.end());
  if (grad_tol > 0) a.insert(a.end(), {"--grad-tol", exact_text(grad_tol)});
  if (max_rounds > 0) a.insert(a.end(), {"--max-rounds", std::to_string(max_rounds)});
  if (certify) a.push_back("--certify");
  if (!output.empty()) a.insert(a.end(), {"--output", output});
  if (!summary.empty()) a.insert(a.end(), {"--summary", summary});
  if (progress) a.push_back("--progress");
  a.insert(a.end(), extra_args.begin(), extra_args.end());
  return a;
}

void CoordinatorOptions::validate() const {
  coordinator::parse_coordinator_options(argv());
}

std::string RunSummary::full_report() const {
  std::ostringstream out;
  out.precision(3);
  out << "run " << run_id << ": "
      << (exit_code == 0 ? "done" : "failed (exit code " + std::to_string(exit_code) + ")")
      << ", coordinator " << std::fixed << wall_s << " s\n";
  out << "summary: " << (summary_json.empty() ? "none\n" : "\n" + summary_json);
  return out.str();
}

RunSummary run_coordinator(const CoordinatorOptions& options) {
  options.validate();
  const auto t0 = std::chrono::steady_clock::now();
  CoordinatorOptions o = options;
  std::string temporary;  // the summary is read back even when the caller wants no file
  if (o.summary.empty()) {
    char tmpl[] = "/tmp/tessera-summary-XXXXXX";
    const int fd = mkstemp(tmpl);
    if (fd >= 0) {
      close(fd);
      temporary = o.summary = tmpl;
    }
  }
  std::vector<std::string> strings = {"tessera-coordinator"};
  const std::vector<std::string> args = o.argv();
  strings.insert(strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  RunSummary r;
  r.exit_code = coordinator::coordinator_main(static_cast<int>(strings.size()), argv.data());
  r.run_id = o.session.run_id;
  if (!o.summary.empty()) r.summary_json = slurp(o.summary);
  if (!temporary.empty()) std::remove(temporary.c_str());
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace tessera::dds
