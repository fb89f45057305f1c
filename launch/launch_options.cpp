#include "launch/launch_options.hpp"

#include <cstdio>
#include <set>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "cli/arguments.hpp"
#include "cli/robot_files.hpp"
#include "launch/forwarded_flags.hpp"
#include "launch/solve_only_flags.hpp"
#include "transport/security.hpp"

namespace tessera::launch {

namespace {

// %s: the forwarded flags (forwarded_flags.hpp), the loss options (launch_loss_policy.hpp),
// then the shared DDS session options (session_args.hpp).
constexpr const char* kHelp =
    R"(usage: tessera launch [GRAPH.g2o | ROBOT_FILES_DIR | R0.g2o,R1.g2o,...] --agents N [options]

Runs a distributed solve on this host as separate processes: one tessera-coordinator and N
tessera-agent processes (robot k reads its sequential share of GRAPH, or the k-th robot file
of a folder or list, as written by tessera generate --split; a dpgo measurement CSV, file or
folder of robot<k>/measurements.csv, gives robot k the CSV's robot k: --agents = robots)
talking peer to peer
over Fast DDS. Prints progress (round, cost, gradient norm) while it runs and the JSON
summary at the end. Any failing process (a dead agent only with --on-agent-loss stop, the
default), the time limit or Ctrl-C stops every process; the exit code is then non-zero.
Without GRAPH, a 3D grid is generated into a temporary folder
(tessera generate --kind grid3d --poses P --robots N). The agents initialise like
`tessera solve` (--init, default chordal), so both give the same iterates.

options:
  --agents N           number of agent processes, 1..64                     [3]
  --algorithm NAME     rbcd | rbcd++ | irbcd                                 [irbcd]
  --partition PRESET   auto | sequential | fast | eco | strong | highest    [auto]
                       auto: fast below 2000 poses, eco from there
  --init NAME          chordal | distributed | file (VERTEX poses)           [chordal]
  --grad-tol X         stop when the gradient norm is at most X (> 0)       [0.01]
  --max-rounds K       round limit (0 = the solver's default, 10000)        [0]
  --rank R             relaxation rank (0 = the solver's default, 5)        [0]
  --seed S             solver seed                                           [1]
  --certify            after the solve, the agents certify global optimality distributedly
                       and escape saddles up the staircase (default: on). certified = the
                       exact interface test proved a lower bound f_lb on the optimum (weak
                       duality) with f(X) - f_lb <= 1e-4 max(1, |f(X)|), or without that test
                       LOBPCG's estimate at |grad f| <= 1e-4 max(1, |f|); the JSON has
                       certificate_method, dual_lower_bound, suboptimality_bound (cost - f_lb)
                       and certificate_grad_norm (docs/distributed-certification.md)
  --no-certify         skip the certificate
  --json FILE          also write the summary to FILE
  --keep-logs DIR      keep the processes' logs in DIR (created when missing; default: a
                       temporary folder removed at the end); with TESSERA_DDS_TRACE=1 they
                       hold each process's discovery and set-up steps
  --timeout S          time limit of the whole run, seconds                 [600]
  --poses P            poses of the generated graph (without GRAPH)         [1000]
%s%s  --quiet              no progress lines
  --help               this text

advanced (how the processes start and talk; the defaults measured best):
  --status-relay       round statuses through agent 0, one bundle per step instead of
                       all to all (fewer DDS deliveries, one more hop; not with
                       --on-agent-loss continue; the default)
  --no-status-relay    round statuses all to all (every agent to every agent)
  --no-fork-server     start tessera-coordinator and tessera-agent with exec, each
                       loading Fast DDS itself (default: one tessera-fork-server loads it
                       once and forks them; see docs/dds-runtime.md, "Fork server")
  --no-agents-batch    the agents start as normal threads (default: SCHED_BATCH until
                       their assignment, so that their start-up's wake-ups do not preempt
                       the coordinator's partition of GRAPH; fork server and a whole file
                       only)

DDS session options (passed on to the coordinator and every agent):
%s
exit codes: 0 done, 1 the run failed (a process failed, or the time limit), 2 bad options,
130 interrupted.
)";

}  // namespace

std::vector<std::string> LaunchOptions::robot_files() const {
  // A dpgo CSV (file or folder) becomes robot files only when the run starts (launch.cpp).
  return graph.empty() || is_dpgo_csv(graph) ? std::vector<std::string>{}
                                             : cli::robot_files_of(graph);
}

void LaunchOptions::validate() const {
  const std::vector<std::string> files = robot_files();
  if (!files.empty() && static_cast<std::size_t>(agents) != files.size())
    throw InputError("launch: " + std::to_string(files.size()) + " robot files in " + graph +
                     " but --agents " + std::to_string(agents));
  if (agents < 1 || agents > 64) throw InputError("launch: --agents must be in 1..64");
  if (algorithm != "rbcd" && algorithm != "rbcd++" && algorithm != "irbcd")
    throw InputError("launch: --algorithm '" + algorithm + "' is not one of rbcd, rbcd++, irbcd");
  parse_init(init);  // InputError naming the valid ones
  if (!(grad_tol > 0)) throw InputError("launch: --grad-tol must be > 0");
  if (max_rounds < 0) throw InputError("launch: --max-rounds must be >= 0");
  if (rank < 0) throw InputError("launch: --rank must be >= 0");
  if (seed < 0) throw InputError("launch: --seed must be >= 0");
  if (!net.session.security_dir.empty())  // every identity is needed on this host
    for (long k = -1; k < agents; ++k)
      transport::security_files(net.session.security_dir,
                                transport::security_identity(k < 0, static_cast<std::uint32_t>(k)));
  if (!(timeout_s > 0)) throw InputError("launch: --timeout must be > 0");
  if (graph.empty() && poses < agents)
    throw InputError("launch: --poses must be at least --agents");
  loss.validate();
  for (const auto& [name, value] : forwarded) {
    const ForwardedFlag* f = find_forwarded_flag(name);
    if (!f) throw InputError("launch: '" + name + "' is not a forwarded flag");
    if (f->check) f->check(value);
  }
}

LaunchOptions parse_launch_options(const std::vector<std::string>& argv) {
  refuse_solve_only_flags(argv, solve_only_flags());
  std::set<std::string> valued = {"agents",   "algorithm",  "partition", "init",
                                  "grad-tol", "max-rounds", "rank",      "seed",
                                  "json",     "timeout",    "poses",     "keep-logs"};
  std::set<std::string> switches = {"quiet",          "certify",         "no-certify",
                                    "no-fork-server", "no-agents-batch", "status-relay",
                                    "no-status-relay"};
  for (const auto& n : launch_loss_option_names()) valued.insert(n);
  for (const ForwardedFlag& f : forwarded_flags()) (f.valued ? valued : switches).insert(f.name);
  const cli::Arguments args(argv, cli::with_session_options(valued, cli::SessionArgsFor::kLaunch),
                            switches);
  if (args.positional().size() > 1)
    throw InputError("launch: at most one GRAPH argument, got " +
                     std::to_string(args.positional().size()));
  LaunchOptions o;
  if (!args.positional().empty()) o.graph = args.positional()[0];
  const std::vector<std::string> files = o.robot_files();
  o.agents = args.get_long("agents", files.empty() ? 3 : static_cast<long>(files.size()));
  o.algorithm = args.get_or("algorithm", o.algorithm);
  o.partition = args.get_or("partition", o.partition);
  o.init = args.get_or("init", init_name(DistributedOptions{}.initialization));
  o.init_given = args.has("init");
  o.grad_tol = args.get_double("grad-tol", o.grad_tol);
  o.max_rounds = args.get_long("max-rounds", o.max_rounds);
  o.rank = args.get_long("rank", o.rank);
  o.seed = args.get_long("seed", o.seed);
  o.json = args.get_or("json", "");
  o.keep_logs = args.get_or("keep-logs", "");
  o.timeout_s = args.get_double("timeout", o.timeout_s);
  o.poses = args.get_long("poses", o.poses);
  o.quiet = args.has("quiet");
  if (args.has("certify") && args.has("no-certify"))
    throw InputError("launch: --certify and --no-certify exclude each other");
  o.certify = !args.has("no-certify");
  if (args.has("status-relay") && args.has("no-status-relay"))
    throw InputError("launch: --status-relay and --no-status-relay exclude each other");
  o.status_relay = !args.has("no-status-relay");
  o.fork_server = !args.has("no-fork-server");
  o.agents_batch = !args.has("no-agents-batch");
  o.net = cli::parse_session_args(args, cli::SessionArgsFor::kLaunch);
  o.loss = parse_launch_loss_options(args);
  o.choose_transport = !args.has("transport");
  o.choose_lease = !args.has("lease");
  if (!args.has("run-id")) o.net.session.run_id.clear();  // launch() makes a fresh one
  for (const ForwardedFlag& f : forwarded_flags())
    if (args.has(f.name)) o.forwarded.emplace_back(f.name, f.valued ? *args.get(f.name) : "");
  o.validate();
  return o;
}

bool wants_launch_help(const std::vector<std::string>& argv) {
  for (const auto& a : argv)
    if (a == "--help" || a == "-h") return true;
  return false;
}

std::string launch_help() {
  const std::string forwarded = forwarded_flags_help();
  const std::string loss = launch_loss_help();
  const std::string session = cli::session_options_help(cli::SessionArgsFor::kLaunch);
  const int n = std::snprintf(nullptr, 0, kHelp, forwarded.c_str(), loss.c_str(), session.c_str());
  std::string out(static_cast<std::size_t>(n) + 1, '\0');
  std::snprintf(out.data(), out.size(), kHelp, forwarded.c_str(), loss.c_str(), session.c_str());
  out.resize(static_cast<std::size_t>(n));
  return out;
}

}  // namespace tessera::launch
