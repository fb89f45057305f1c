// run_agent() of the public API (<tessera/dds/agent.hpp>): the options become tessera-agent's
// command line, so a hosted agent and the executable parse, check and run the same way.

#include <chrono>
#include <sstream>
#include <tessera/dds/agent.hpp>

#include "agent/agent_entry.hpp"
#include "agent/agent_options.hpp"
#include "io/number_text.hpp"

namespace tessera::dds {

std::vector<std::string> AgentOptions::argv() const {
  std::vector<std::string> a = {
      "--graph", graph, "--robots", std::to_string(robots), "--id", std::to_string(id)};
  const std::vector<std::string> s = session.argv();
  a.insert(a.end(), s.begin(), s.end());
  if (round_timeout_s != AgentOptions{}.round_timeout_s)
    a.insert(a.end(), {"--round-timeout", exact_text(round_timeout_s)});
  if (!output.empty()) a.insert(a.end(), {"--output", output});
  if (!checkpoint_dir.empty()) a.insert(a.end(), {"--checkpoint-dir", checkpoint_dir});
  if (checkpoint_every != 1)
    a.insert(a.end(), {"--checkpoint-every", std::to_string(checkpoint_every)});
  if (verbose) a.push_back("--verbose");
  a.insert(a.end(), extra_args.begin(), extra_args.end());
  return a;
}

void AgentOptions::validate() const {
  agent::parse_agent_options(argv());
}

std::string AgentResult::full_report() const {
  std::ostringstream out;
  out.precision(3);
  out << "agent " << id << " of run " << run_id << ": "
      << (exit_code == 0 ? "done" : "failed (exit code " + std::to_string(exit_code) + ")") << ", "
      << std::fixed << wall_s << " s\n";
  if (!output.empty()) out << "poses written to " << output << "\n";
  return out.str();
}

AgentResult run_agent(const AgentOptions& options) {
  options.validate();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::string> strings = {"tessera-agent"};
  const std::vector<std::string> args = options.argv();
  strings.insert(strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  AgentResult r;
  r.exit_code = agent::agent_main(static_cast<int>(strings.size()), argv.data());
  r.id = options.id;
  r.run_id = options.session.run_id;
  if (r.exit_code == 0) r.output = options.output;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace tessera::dds
