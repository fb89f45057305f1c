#include "agent/online_agent_options.hpp"

#include <set>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "rebalance_args.hpp"
#include "run_wide_args.hpp"
#include "step_coarse_args.hpp"
#include "transport/run_identity.hpp"

namespace tessera::agent {

namespace {

const char* const kOnlineUsage =
    R"(usage: tessera-agent --online --robots N --id I --run-id ID [options]

One robot's agent of an online run (docs/online.md): reads every robot's batches from the
DDS topic tessera_graph_stream (partition = run id; `tessera replay` or a front end writes
them), agrees with the other agents on the batches that enter at each epoch boundary,
solves the grown graph from the current estimate until the gradient is under --grad-tol,
idles without sending anything while nothing is new, and certifies the estimate when every
robot has sent its last batch. Robot I's block is this agent's.

options:
  --robots N          robots = agents of the run (required)
  --id I              this agent's robot, 0..N-1 (required)
  --run-id ID         the run (required)
  --domain D          DDS domain 0..232                              [from the run id]
  --algorithm A       rbcd, rbcd++ or irbcd                          [irbcd]
  --rank R            lifted rank r >= d                             [5]
  --grad-tol G        gradient-norm tolerance of every solve, > 0    [0.01]
  --max-rounds K      rounds per solve at most                       [10000]
  --no-certify        no certificate at the end
  --timeout S         give up when a peer sends nothing for S seconds [120]
  --lease S           DDS participant lease: a member silent S seconds is lost, 0.2..60 [2]
  --on-agent-loss A   what a member whose DDS liveliness lapsed does to the run: stop
                      (the others stop after --timeout, naming it) or continue (the
                      survivors take over its block and its robot's stream)  [stop]
  --json FILE         write this agent's summary (the lead's has the final answer: agent
                      0's, or after its loss the lowest surviving agent's)
  --certify-iters K   certificate iteration cap (LOBPCG)               [300]
  --step-solver S     how a solve gets the gradient back under --grad-tol: newton
                      (distributed Newton steps from the warm start) or rounds [newton]
  --newton-after T    newton: block-coordinate rounds first, down to ||grad f|| <= T
                                                                     [none]
%STEPCOARSE%  --first-step-factors new|grown  newton: the preconditioner of a step's first Newton
                      step: the grown blocks' new factors, or their held factors with the
                      new poses appended, new ones built at the first accepted Newton
                      step's point (docs/online.md)                  [new]
  --tangent-dots split|sequential  the tangent preconditioner's backward dot products as
                      four partial sums, or CHOLMOD's sequential sums (its bits) [split]
%GROWTHLOCAL%  --certify-every S   also certify the graph received so far every S seconds (the lead's
                      clock; at the next epoch that brought data, once the graph is
                      connected; no staircase climb)                  [0 = off]
  --publish-every S   publish this robot's current estimate (rounded to SE(d)) on topic
                      tessera_online_estimate every S seconds, and at the end [0 = off]
  --tum-dir DIR       write DIR/robot<I>.tum (TUM, timestamp = pose index) at every
                      publication and at the end
  --verbose           print each epoch (members, what entered, solve or idle)
  --help              this text

The --step-coarse options, --first-step-factors, --tangent-dots, --refactor-growth,
--local-threshold, --no-local-rounds and the re-partition's below are the same on every
agent of the run (the coarse correction adds message steps to every agent's Newton steps,
the local rounds decide which agents send each round, the others change every agent's
arithmetic; each agent moves the blocks itself): an agent whose options differ from the
lead's stops with exit code 2 naming the option.

re-partition:
%REBALANCE%

exit codes: 0 done, 1 the run failed (a peer went silent, or this agent was counted lost and
its block taken over), 2 bad options or input.
)";

}  // namespace

const char* online_agent_usage() {
  static const std::string text = [] {
    std::string t = kOnlineUsage;
    const auto put = [&t](const std::string& mark, const char* text) {
      t.replace(t.find(mark), mark.size(), text);
    };
    put("%STEPCOARSE%", cli::kStepCoarseHelp);
    put("%GROWTHLOCAL%", cli::kGrowthAndLocalRoundsHelp);
    put("%REBALANCE%\n", cli::kRebalanceHelp);
    return t;
  }();
  return text.c_str();
}

OnlineAgentOptions parse_online_agent_options(const std::vector<std::string>& argv) {
  std::set<std::string> valued = {"robots",        "id",      "run-id",        "domain",
                                  "algorithm",     "rank",    "grad-tol",      "max-rounds",
                                  "timeout",       "json",    "certify-every", "certify-iters",
                                  "publish-every", "tum-dir", "on-agent-loss", "step-solver",
                                  "newton-after",  "lease"};
  valued.insert({"first-step-factors", "tangent-dots", "refactor-growth",
                 "local-threshold"});  // cli/run_wide_args.hpp
  std::set<std::string> switches = {"online", "no-certify", "no-local-rounds", "verbose", "help"};
  for (const char* const* f = cli::kRebalanceValued; *f; ++f) valued.insert(*f);
  for (const char* const* f = cli::kRebalanceSwitches; *f; ++f) switches.insert(*f);
  for (const char* const* f = cli::kStepCoarseValued; *f; ++f) valued.insert(*f);
  const cli::Arguments args(argv, valued, switches);
  OnlineAgentOptions o;
  const auto run_id = args.get("run-id");
  if (!run_id) throw InputError("option --run-id ID is required (see --help)");
  transport::validate_run_id(*run_id);
  o.run_id = *run_id;
  o.robots = static_cast<int>(args.get_long("robots", 0));
  o.id = static_cast<int>(args.get_long("id", -1));
  if (o.robots < 1) throw InputError("option --robots N is required (N >= 1)");
  if (o.id < 0 || o.id >= o.robots)
    throw InputError("option --id: must be 0.." + std::to_string(o.robots - 1));
  const long domain = args.get_long("domain", transport::domain_for_run(o.run_id));
  if (domain < 0 || domain > transport::kMaxDomain)
    throw InputError("option --domain: must be 0.." + std::to_string(transport::kMaxDomain));
  o.domain = static_cast<int>(domain);
  DistributedOptions& s = o.online.solver;
  s.algorithm = parse_algorithm(args.get_or("algorithm", "irbcd"));
  s.rank = static_cast<int>(args.get_long("rank", 5));
  s.grad_norm_tol = args.get_double("grad-tol", 0.01);
  if (!(s.grad_norm_tol > 0)) throw InputError("option --grad-tol: must be > 0");
  s.max_rounds = static_cast<int>(args.get_long("max-rounds", 10000));
  o.online.certify_at_end = !args.has("no-certify");
  s.staircase.certificate.max_iterations =
      static_cast<int>(args.get_long("certify-iters", s.staircase.certificate.max_iterations));
  o.timeout_s = args.get_double("timeout", 120.0);
  if (!(o.timeout_s > 0)) throw InputError("option --timeout: must be > 0");
  o.lease_s = args.get_double("lease", o.lease_s);
  if (!(o.lease_s >= 0.2 && o.lease_s <= 60)) throw InputError("option --lease: must be 0.2..60");
  const std::string loss = args.get_or("on-agent-loss", "stop");
  if (loss != "stop" && loss != "continue")
    throw InputError("option --on-agent-loss: '" + loss + "' is not one of stop, continue");
  o.continue_on_loss = loss == "continue";
  o.json = args.get_or("json", "");
  o.verbose = args.has("verbose");
  o.certify_every_s = args.get_double("certify-every", 0.0);
  if (!(o.certify_every_s >= 0)) throw InputError("option --certify-every: must be >= 0");
  o.publish_every_s = args.get_double("publish-every", 0.0);
  if (!(o.publish_every_s >= 0)) throw InputError("option --publish-every: must be >= 0");
  o.tum_dir = args.get_or("tum-dir", "");
  const std::string step_solver = args.get_or("step-solver", "newton");
  if (step_solver != "newton" && step_solver != "rounds")
    throw InputError("option --step-solver: '" + step_solver + "' is not one of newton, rounds");
  o.online.newton_steps = step_solver == "newton";
  o.online.newton_after_grad_tol = args.get_double("newton-after", o.online.newton_after_grad_tol);
  cli::parse_step_coarse_options(args, o.online);
  o.online.first_step_on_grown_factors = cli::first_step_on_grown_factors_of(args);
  s.block_update.tangent_split_dots = cli::tangent_split_dots_of(args);
  cli::parse_growth_and_local_rounds(args, o.online);
  o.online.rebalance = cli::parse_rebalance_options(args);
  o.online.validate();
  return o;
}

}  // namespace tessera::agent
