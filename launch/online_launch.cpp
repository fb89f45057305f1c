#include "launch/online_launch.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tessera/util/input_error.hpp>
#include <thread>
#include <utility>
#include <vector>

#include "arguments.hpp"
#include "launch/launch.hpp"
#include "launch/launch_loss_policy.hpp"
#include "launch/solve_only_flags.hpp"
#include "rebalance_args.hpp"
#include "run_wide_args.hpp"
#include "step_coarse_args.hpp"
#include "transport/run_identity.hpp"

namespace tessera::launch {

namespace {

const char* const kOnlineHelp =
    R"(usage: tessera launch GRAPH --agents N --online [options]

An online run on this host (docs/online.md): N online agents (tessera-agent --online, one
per robot) and a replay of GRAPH onto the graph stream (tessera replay), robot r owning
the contiguous ids [r n/N, (r+1) n/N) of a g2o file, or the per-robot files of
`generate --split` (a folder or a comma-separated list). The agents absorb the data while
it streams in, solve the grown graph from their current estimate, idle while nothing is
new, and certify the estimate after every robot's last batch.

  --agents N          agents = robots (required)
  --rate R            poses per second per robot                     [10]
  --speedup X         play X times faster than real time             [1]
  --start S0,S1,...   seconds (before the speedup) each robot starts [all 0]
  --run-id ID         the run's id                                   [a fresh one]
  --domain D          DDS domain                                     [from the run id]
  --algorithm A       rbcd, rbcd++ or irbcd                          [irbcd]
  --rank R            lifted rank                                    [5]
  --grad-tol G        gradient-norm tolerance of every solve         [0.01]
  --max-rounds K      rounds per solve at most                       [10000]
  --no-certify        no certificate at the end
  --timeout S         an agent gives up when a peer is silent S seconds [120]
  --lease S           the agents' DDS participant lease: a member silent S seconds is lost
                      (a loaded host may not schedule a process for seconds), 0.2..60 [2]
  --on-agent-loss A   stop: a failed agent stops the run; continue: the survivors take over
                      a lost agent's block and its robot's stream, and the run goes on [stop]
  --certify-iters K   certificate iteration cap (LOBPCG)             [300]
  --certify-every S   also certify the graph received so far every S seconds
  --step-solver S     newton or rounds: how the agents solve a grown graph [newton]
  --newton-after T    newton: rounds first, down to ||grad f|| <= T  [none]
%STEPCOARSE%  --first-step-factors new|grown  newton: the preconditioner of a step's first Newton
                      step: the grown blocks' new factors, or their held factors with the
                      new poses appended (docs/online.md)            [new]
  --tangent-dots split|sequential  the tangent preconditioner's backward dot products as
                      four partial sums, or CHOLMOD's sequential sums (its bits) [split]
%GROWTHLOCAL%  --publish-every S   each agent publishes its robot's estimate every S seconds
                      (topic tessera_online_estimate)
  --tum-dir DIR       per-robot TUM snapshots DIR/robot<r>.tum, rewritten at every
                      publication and at the end
  --json FILE         the summary: the lead's (agent 0, or the lowest surviving agent:
                      updates, final answer) and every agent's traffic under "agents"
  --keep-logs DIR     keep the processes' logs and summaries in DIR

The --step-coarse options, --first-step-factors, --tangent-dots, --refactor-growth,
--local-threshold, --no-local-rounds and the re-partition's below are passed to every agent
(the coarse correction adds message steps to every agent's Newton steps, the local rounds
decide which agents send each round, the others change every agent's arithmetic; each agent
moves the blocks itself), so all use the same. Options of tessera solve --online that a run
over DDS cannot use (its in-process evaluation: --checkpoints, --baseline...) are refused,
naming the reason.

re-partition:
)";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A number field of a flat summary written by cli::JsonObject (`"key": value`).
std::string field_text(const std::string& json, const std::string& key) {
  const std::string tag = "\"" + key + "\": ";
  const std::size_t at = json.find(tag);
  if (at == std::string::npos) return "null";
  const std::size_t begin = at + tag.size();
  const std::size_t end = json.find_first_of(",\n}", begin);
  return json.substr(begin, end - begin);
}

struct Process {
  std::string name;
  pid_t pid = -1;
  int code = -1;
  std::string log;
};

Process start(const std::string& name, const std::vector<std::string>& argv,
              const std::string& log) {
  Process p{name, -1, -1, log};
  p.pid = fork();
  if (p.pid < 0) throw std::runtime_error("launch: fork failed");
  if (p.pid == 0) {
    FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (f) dup2(fileno(stdout), 2);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "cannot run %s\n", args[0]);
    _exit(127);
  }
  return p;
}

}  // namespace

bool wants_online_launch(const std::vector<std::string>& argv) {
  for (const auto& a : argv)
    if (a == "--online") return true;
  return false;
}

int run_online_launch(const std::vector<std::string>& argv) {
  for (const auto& a : argv)
    if (a == "--help" || a == "-h") {
      std::string help = kOnlineHelp;
      for (const auto& [mark, text] :
           {std::pair<std::string, const char*>{"%STEPCOARSE%", cli::kStepCoarseHelp},
            {"%GROWTHLOCAL%", cli::kGrowthAndLocalRoundsHelp}})
        help.replace(help.find(mark), mark.size(), text);
      std::fputs(help.c_str(), stdout);
      std::fputs(cli::kRebalanceHelp, stdout);
      return 0;
    }
  // Launch's options that every agent gets as they are.
  static const char* const kForwarded[] = {"algorithm",       "rank",
                                           "grad-tol",        "timeout",
                                           "certify-every",   "certify-iters",
                                           "publish-every",   "tum-dir",
                                           "on-agent-loss",   "step-solver",
                                           "newton-after",    "lease",
                                           "max-rounds",      "first-step-factors",
                                           "tangent-dots",    "refactor-growth",
                                           "local-threshold", nullptr};
  std::set<std::string> valued = {"agents", "rate",   "speedup", "start",
                                  "run-id", "domain", "json",    "keep-logs"};
  std::set<std::string> switches = {"online", "no-certify", "no-local-rounds"};
  for (const char* const* f = kForwarded; *f; ++f) valued.insert(*f);
  for (const char* const* f = cli::kRebalanceValued; *f; ++f) valued.insert(*f);
  for (const char* const* f = cli::kRebalanceSwitches; *f; ++f) switches.insert(*f);
  for (const char* const* f = cli::kStepCoarseValued; *f; ++f) valued.insert(*f);
  refuse_solve_only_flags(argv, online_solve_only_flags());
  const cli::Arguments args(argv, valued, switches);
  if (args.positional().size() != 1)
    throw InputError("launch --online: expected one GRAPH argument (see --online --help)");
  const std::string graph = args.positional().front();
  if (!std::filesystem::exists(graph)) throw InputError(graph, 0, "cannot open the graph");
  const long agents = args.get_long("agents", 0);
  if (agents < 1 || agents > 256) throw InputError("option --agents: must be 1..256");
  std::string run_id = args.get_or(
      "run-id",
      "online-" + std::to_string(getpid()) + "-" +
          std::to_string(std::chrono::steady_clock::now().time_since_epoch().count() % 1000000));
  transport::validate_run_id(run_id);
  // The flag of the offline launch (its loss options --rejoin-timeout, --replicas and
  // --replica-every are not options of an online launch).
  const bool continue_on_loss =
      parse_launch_loss_options(args).action == AgentLossAction::kContinue;
  if (auto solver = args.get("step-solver"); solver && *solver != "newton" && *solver != "rounds")
    throw InputError("option --step-solver: '" + *solver + "' is not one of newton, rounds");
  if (args.has("newton-after") && !(args.get_double("newton-after", 0.0) > 0))
    throw InputError("option --newton-after: must be > 0");
  if (args.has("lease") &&
      !(args.get_double("lease", 0.0) >= 0.2 && args.get_double("lease", 0.0) <= 60))
    throw InputError("option --lease: must be 0.2..60");
  const long domain = args.get_long("domain", transport::domain_for_run(run_id));
  if (domain < 0 || domain > transport::kMaxDomain)
    throw InputError("option --domain: must be 0.." + std::to_string(transport::kMaxDomain));
  // Checked here: a bad value is named before any start.
  cli::parse_rebalance_options(args);
  cli::first_step_on_grown_factors_of(args);
  cli::tangent_split_dots_of(args);
  if (args.has("max-rounds") && args.get_long("max-rounds", 0) < 1)
    throw InputError("option --max-rounds: must be >= 1");
  OnlineOptions checked;
  cli::parse_step_coarse_options(args, checked);
  cli::parse_growth_and_local_rounds(args, checked);

  if (auto dir = args.get("tum-dir")) {
    std::error_code ec;
    std::filesystem::create_directories(*dir, ec);
    if (ec) throw InputError(*dir, 0, "cannot create the TUM folder: " + ec.message());
  }
  const std::string bin = running_program_dir();
  for (const char* exe : {"tessera-agent", "tessera-replay"})
    if (access((bin + "/" + exe).c_str(), X_OK) != 0)
      throw InputError(std::string("launch --online needs ") + bin + "/" + exe);
  std::string work;
  if (auto keep = args.get("keep-logs")) {
    std::filesystem::create_directories(*keep);
    work = *keep;
  } else {
    char tmpl[] = "/tmp/tessera-online-XXXXXX";
    if (!mkdtemp(tmpl)) throw std::runtime_error("launch: cannot create a temporary folder");
    work = tmpl;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Process> procs;
  const std::vector<std::string> common = {"--run-id", run_id, "--domain", std::to_string(domain)};
  // What every agent gets of launch's own options, in this order.
  std::vector<std::string> forwarded;
  auto forward_valued = [&](const char* flag) {
    if (auto v = args.get(flag)) forwarded.insert(forwarded.end(), {std::string("--") + flag, *v});
  };
  for (const char* const* flag = kForwarded; *flag; ++flag) forward_valued(*flag);
  for (const char* const* flag = cli::kRebalanceValued; *flag; ++flag) forward_valued(*flag);
  for (const char* const* flag = cli::kStepCoarseValued; *flag; ++flag) forward_valued(*flag);
  for (const char* const* flag = cli::kRebalanceSwitches; *flag; ++flag)
    if (args.has(*flag)) forwarded.push_back(std::string("--") + *flag);
  for (const char* flag : {"no-certify", "no-local-rounds"})
    if (args.has(flag)) forwarded.push_back(std::string("--") + flag);
  for (long i = 0; i < agents; ++i) {
    std::vector<std::string> a = {bin + "/tessera-agent", "--online", "--robots",
                                  std::to_string(agents), "--id",     std::to_string(i)};
    a.insert(a.end(), common.begin(), common.end());
    a.insert(a.end(), forwarded.begin(), forwarded.end());
    a.push_back("--json");
    a.push_back(work + "/agent-" + std::to_string(i) + ".json");
    procs.push_back(
        start("agent " + std::to_string(i), a, work + "/agent-" + std::to_string(i) + ".log"));
  }
  {
    std::vector<std::string> r = {bin + "/tessera-replay", graph};
    r.insert(r.end(), common.begin(), common.end());
    // A g2o file is split among the agents; robot files say who owns what.
    if (std::filesystem::is_regular_file(graph) && graph.find(',') == std::string::npos) {
      r.push_back("--robots");
      r.push_back(std::to_string(agents));
    }
    for (const char* flag : {"rate", "speedup", "start"})
      if (auto v = args.get(flag)) {
        r.push_back(std::string("--") + flag);
        r.push_back(*v);
      }
    // Plays once every agent reads the stream, so the timeline starts with the run.
    r.insert(r.end(), {"--wait-readers", std::to_string(agents), "--linger", "1", "--json",
                       work + "/replay.json"});
    procs.push_back(start("replay", r, work + "/replay.log"));
  }
  // Wait; the first failure stops the others (with --on-agent-loss continue, a failed agent
  // does not: the survivors take its block over).
  int failed = 0;
  std::vector<long> lost_agents;
  std::size_t running = procs.size();
  while (running > 0) {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) break;
    for (auto& p : procs)
      if (p.pid == pid) {
        p.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        --running;
        const bool agent = &p - procs.data() < agents;
        if (p.code != 0 && continue_on_loss && agent && failed == 0) {
          lost_agents.push_back(static_cast<long>(&p - procs.data()));
          std::fprintf(stderr,
                       "tessera launch: %s ended with exit %d; the others go on without it\n",
                       p.name.c_str(), p.code);
        } else if (p.code != 0 && failed == 0) {
          failed = p.code == 2 ? 2 : 1;
          std::fprintf(stderr, "tessera launch: %s failed (exit %d):\n%s", p.name.c_str(), p.code,
                       read_text(p.log).c_str());
          for (auto& q : procs)
            if (q.code < 0) kill(q.pid, SIGTERM);
        }
      }
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (failed != 0) return failed;
  if (static_cast<long>(lost_agents.size()) == agents)
    throw std::runtime_error("launch: every agent failed");

  // The lead's summary: agent 0's, or after its loss the lowest surviving agent's.
  long lead_id = 0;
  while (std::find(lost_agents.begin(), lost_agents.end(), lead_id) != lost_agents.end()) ++lead_id;
  std::string lead = read_text(work + "/agent-" + std::to_string(lead_id) + ".json");
  const std::size_t close = lead.find_last_of('}');
  if (lead.empty() || close == std::string::npos)
    throw std::runtime_error("launch: agent " + std::to_string(lead_id) + " wrote no summary");
  std::string per_agent;
  for (long i = 0; i < agents; ++i) {
    if (std::find(lost_agents.begin(), lost_agents.end(), i) != lost_agents.end()) continue;
    const std::string j = read_text(work + "/agent-" + std::to_string(i) + ".json");
    per_agent +=
        std::string(per_agent.empty() ? "" : ",\n") + "    {\"agent\": " + std::to_string(i);
    for (const char* key : {"solves", "rounds", "bytes_sent", "messages_sent", "report_bytes",
                            "idle_waits", "publications", "cpu_s", "wall_s"})
      per_agent += std::string(", \"") + key + "\": " + field_text(j, key);
    per_agent += "}";
  }
  const std::string merged = lead.substr(0, close) + ",\n  \"graph\": \"" + graph +
                             "\",\n  \"launch_wall_s\": " + std::to_string(wall_s) +
                             ",\n  \"agents\": [\n" + per_agent + "\n  ]\n}\n";
  std::printf(
      "online run %s: %s poses, %s measurements, %s solves, %s rounds; cost %s, certified %s; "
      "latency median %s s, p95 %s s; %.2f s\n",
      run_id.c_str(), field_text(lead, "total_poses").c_str(),
      field_text(lead, "total_measurements").c_str(), field_text(lead, "solves").c_str(),
      field_text(lead, "rounds").c_str(), field_text(lead, "cost").c_str(),
      field_text(lead, "certified").c_str(), field_text(lead, "latency_median_s").c_str(),
      field_text(lead, "latency_p95_s").c_str(), wall_s);
  if (auto json = args.get("json")) {
    std::ofstream out(*json);
    if (!out) throw InputError(*json, 0, "cannot write the summary");
    out << merged;
  }
  if (!args.has("keep-logs")) std::filesystem::remove_all(work);
  return 0;
}

}  // namespace tessera::launch
