#include "coordinator/coordinator_options.hpp"

#include <cmath>
#include <set>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "arguments.hpp"
#include "robust_args.hpp"
#include "run_wide_args.hpp"
#include "runtime/setup_turns.hpp"

namespace tessera::coordinator {

// %s: the shared DDS session options (cli/session_args.hpp).
const char* const kCoordinatorUsage = R"(usage: tessera-coordinator --agents N [options]

The coordinator of a distributed Tessera run. Waits for N tessera-agent processes of the
same run id, receives their graph structure (edge endpoints only), partitions it, publishes
the assignment and the algorithm options, then gathers every agent's final poses and writes
the merged result. It never receives measurement values.

options:
  --agents N           number of agents of the run (required)
  --run-timeout S      bound on the wait for the final estimates, seconds (default 3600)
  --partition PRESET   auto, sequential, fast, eco, strong or highest (default
                       auto: fast below 2000 poses, else eco)
  --partition-seed K   seed of the partitioner (default 1)
  --partition-time S   cap of the partitioner's search in seconds of wall time (default 0:
                       none; with a cap the partition depends on the machine's speed)
  --rank R             rank r of the relaxation sent to the agents (default 0 = core's, 5)
  --algorithm NAME     solver name sent to the agents (default: core's default)
  --init NAME          initialisation the agents run: chordal | distributed | file (the
                       VERTEX poses) (default: the in-process engine's, chordal)
  --max-rounds K       round limit sent to the agents (default 0 = core's default)
  --grad-tol X         gradient-norm tolerance sent to the agents (default 0 = core's default)
  --rel-cost-tol X     relative cost tolerance sent to the agents (default 0 = core's default)
  --seed K             solver seed sent to the agents (default 1)
  --certify            agents certify the optimum distributedly and climb the staircase
                       after the solve (docs/distributed-certification.md; default off)
  --status-relay       agents send their round statuses to agent 0 alone, which forwards
                       each step's as one bundle to everyone (2N - 1 deliveries a round
                       instead of N^2; same iterates; ignored with --rejoin-timeout or
                       --replicas; docs/dds-runtime.md; default on)
  --no-status-relay    round statuses all to all instead (N^2 deliveries a round)
  --output FILE        write the merged poses as g2o (VERTEX lines only)
  --tum FILE           write the merged poses in the TUM format
  --summary FILE       write a JSON summary of the run
  --graph-name NAME    label of the graph in the summary (default "")
  --graph FILE         the whole g2o file the agents read, if this host has it (tessera launch
                       passes it): its structure is partitioned while the agents start up, and
                       that partition is used if their announced structure is exactly the
                       file's (otherwise, or if FILE cannot be read, the announced structure is
                       partitioned as without it). Only endpoints are kept (default: none)
  --partition-nice N   the nice of the thread that partitions --graph's file while the
                       agents start, relative to this process's, -20..0: at a lower nice it
                       takes most of a core instead of a fair share beside the agents'
                       start-up, which it then delays (needs root or a matching RLIMIT_NICE,
                       else it stays; the summary's partition_nice says what it got)
                       (default 0: the same)
  --progress           print round progress (sum of the agents' cost and gradient norm)
  --progress-interval S  at most one progress line per S seconds besides the first, the
                       restarts and the last; 0 = every round the coordinator sees (every
                       round with --rejoin-timeout or --replicas, else one per progress
                       digest, ~10 a second) (default 0.1)
  --rejoin-timeout S   when an agent process dies, wait up to S seconds for it to be
                       restarted (same id, --checkpoint-dir) and rejoin; every agent then rolls
                       back to a common checkpoint round. 0 = stop the run at once (default 0)
  --replicas K         replicate every agent's measurements and lifted poses to K other
                       agents; an agent lost for good (not back within --rejoin-timeout) then
                       has its block re-partitioned among the survivors, and the run goes on
                       with N-1 agents. 0 = off: the run stops (default 0)
  --replica-every K    rounds between lifted-pose replicas (default 10)
  --coarse-every K     two-level rounds: the agents add a rigid coarse correction of every
                       block every K-th round (docs/irbcd.md, "Coarse correction"); 0 = off
                       (default 0)
  --coarse-space blocks|smoothed  the coarse space: one rigid motion per block, or K rigid
                       pieces per block blended smoothly across their borders (default blocks)
  --coarse-aggregates K  smoothed: pieces per block (default 4)
  --coarse-smoothing S   smoothed: smoothing steps of the blend, 0..8 (default 1)
  --refine newton|auto|none after the rounds, trust-region Newton steps on the whole
                       problem (docs/newton-refine.md); auto: where the team's interface
                       fits the exact interface solves, rounds to gradient 30 then always
                       the refinement, elsewhere only where the rounds stopped short of
                       their limit (default auto)
  --refine-grad-tol T, --refine-rel-tol F
                       its stops: ||grad f|| <= T, or a step lowered f by < F f (0 = the
                       defaults, 1e-6 and 1e-7)
  --refine-sigma one|every|solve  with its interface solves, agent 0 factors the interface
                       matrix and sends its factor (one), every agent factors it (every),
                       or agent 0 alone factors it and sends each agent its part of every
                       solve (solve; default)
  --tangent-dots split|sequential  the tangent preconditioner's backward dot products as
                       four partial sums, or CHOLMOD's sequential sums (its bits), in every
                       agent (default split)
  --setup-at-once K    at most K agents run the distributed initialisation's local chordal
                       solve at once (agent a after agent a - K): those factorizations are
                       the set-up's memory peak; 0 = all at once (default 8)
  --robust none|gnc-tls|pcm-gnc  gnc-tls: reject outlier measurements by graduated
                       non-convexity with a truncated least-squares cost, then solve (and
                       with --certify certify) the kept ones; every agent weighs the
                       measurements of its lower pose ids; pcm-gnc: agent 0 first drops
                       closures outside the largest pairwise-consistent set
                       (docs/robust.md) (default none)
  --inlier-threshold C, --inlier-quantile P, --gnc-max-outer K, --gnc-mu-step S,
  --gnc-inner-rounds K, --known-inliers odometry|none, --gnc-probes K,
  --gnc-probe-ratio R, --gnc-final-refine newton|none, --gnc-cluster-probes K,
  --gnc-pass-refine auto|none, --gnc-mu-step-max S, --gnc-newton-mu-step-max S,
  --gnc-mu-hold falls|crossings, --gnc-step-trust R, --gnc-jump-side both|beyond,
  --gnc-jump-band-max M, --gnc-probe-cut always|after-passes|auto,
  --gnc-step-sigma every|refine-sigma
                       the GNC options, as for `tessera solve` (docs/robust.md)
  --gnc-inner-iterations K, --gnc-swap-probes K
                       accepted for `tessera solve`'s option set; they are the centralized
                       GNC's and change nothing in a distributed run
  --rejected FILE      write the rejected measurement indices (from 0 over the EDGE lines)
  --gnc-solver-start   GNC starts from --init's poses, not from the known inliers'
                       distributed initialization (tessera launch passes it with --init)
  --reference-cost F   the graph's optimal cost f*, known from elsewhere (tessera solve
                       --algorithm centralized): the summary reports the final cost's
                       relative gap to it, rel_gap_to_reference = (cost - F) / F; F > 0
                       (default: none)
  --status-interval S  print a status line (agents alive, their rounds, lagging or lost
                       agents) every S seconds and on changes; 0 = off (default 5)
  --verbose            print each phase
  --help               this text

DDS session options (shared with tessera-agent and tessera launch):
%s
exit codes: 0 done, 1 the run failed (lost agent, abort, timeout), 2 bad options or input,
128+signal when interrupted (SIGINT 130, SIGTERM 143).
)";

CoordinatorOptions parse_coordinator_options(const std::vector<std::string>& argv) {
  std::set<std::string> valued = cli::with_session_options({"agents",
                                                            "run-timeout",
                                                            "partition",
                                                            "partition-seed",
                                                            "partition-time",
                                                            "partition-nice",
                                                            "rank",
                                                            "algorithm",
                                                            "init",
                                                            "max-rounds",
                                                            "grad-tol",
                                                            "rel-cost-tol",
                                                            "seed",
                                                            "output",
                                                            "tum",
                                                            "summary",
                                                            "graph-name",
                                                            "rejoin-timeout",
                                                            "status-interval",
                                                            "progress-interval",
                                                            "replicas",
                                                            "replica-every",
                                                            "coarse-every",
                                                            "coarse-space",
                                                            "coarse-aggregates",
                                                            "coarse-smoothing",
                                                            "refine",
                                                            "refine-grad-tol",
                                                            "refine-rel-tol",
                                                            "refine-sigma",
                                                            "setup-at-once",
                                                            "reference-cost",
                                                            "gnc-cluster-probes",
                                                            "tangent-dots"},
                                                           cli::SessionArgsFor::kProcess);
  valued.insert("graph");
  for (const char* const* r = cli::kRobustValued; *r; ++r) valued.insert(*r);
  cli::Arguments args(argv, valued,
                      {"progress", "verbose", "help", "certify", "status-relay", "no-status-relay",
                       "gnc-solver-start"});
  if (!args.positional().empty())
    throw InputError("unexpected argument '" + args.positional().front() + "' (see --help)");
  CoordinatorOptions a;
  if (!args.has("agents")) throw InputError("option --agents is required (see --help)");
  long agents = args.get_long("agents", 0);
  if (agents < 1 || agents > 1000) throw InputError("option --agents: must be 1..1000");
  a.agents = static_cast<std::uint32_t>(agents);
  a.net = cli::parse_session_args(args, cli::SessionArgsFor::kProcess);
  a.run_timeout_s = args.get_double("run-timeout", a.run_timeout_s);
  if (!(a.run_timeout_s > 0)) throw InputError("option --run-timeout: must be positive");
  a.partition = args.get_or("partition", a.partition);
  auto nonneg = [&](const char* name, long fallback) {
    long v = args.get_long(name, fallback);
    if (v < 0) throw InputError(std::string("option --") + name + ": must not be negative");
    return v;
  };
  a.partition_seed = static_cast<std::uint64_t>(nonneg("partition-seed", 1));
  a.partition_time_s = args.get_double("partition-time", 0);
  if (!(a.partition_time_s >= 0))
    throw InputError("option --partition-time: must be >= 0 seconds (0 = no cap)");
  const long nice = args.get_long("partition-nice", a.partition_nice);
  if (nice < -20 || nice > 0) throw InputError("option --partition-nice: must be -20..0");
  a.partition_nice = static_cast<int>(nice);
  a.rank = static_cast<std::uint32_t>(nonneg("rank", 0));
  a.algorithm = args.get_or("algorithm", "");
  a.init = args.get_or("init", init_name(DistributedOptions{}.initialization));
  parse_init(a.init);  // throws InputError naming the valid ones
  a.max_rounds = static_cast<std::uint32_t>(nonneg("max-rounds", 0));
  a.grad_tol = args.get_double("grad-tol", 0);
  a.rel_cost_tol = args.get_double("rel-cost-tol", 0);
  if (a.grad_tol < 0) throw InputError("option --grad-tol: must not be negative");
  if (a.rel_cost_tol < 0) throw InputError("option --rel-cost-tol: must not be negative");
  a.seed = static_cast<std::uint64_t>(nonneg("seed", 1));
  a.output = args.get_or("output", "");
  a.tum = args.get_or("tum", "");
  a.summary = args.get_or("summary", "");
  a.graph_name = args.get_or("graph-name", "");
  a.graph = args.get_or("graph", "");
  a.progress = args.has("progress");
  a.rejoin_timeout_s = args.get_double("rejoin-timeout", a.rejoin_timeout_s);
  if (!(a.rejoin_timeout_s >= 0 && a.rejoin_timeout_s <= 86400))
    throw InputError("option --rejoin-timeout: must be 0..86400 seconds");
  a.status_interval_s = args.get_double("status-interval", a.status_interval_s);
  a.progress_interval_s = args.get_double("progress-interval", a.progress_interval_s);
  if (!(a.progress_interval_s >= 0 && a.progress_interval_s <= 3600))
    throw InputError("option --progress-interval: must be 0..3600 seconds");
  if (!(a.status_interval_s >= 0 && a.status_interval_s <= 86400))
    throw InputError("option --status-interval: must be 0..86400 seconds");
  a.replicas = static_cast<std::uint32_t>(nonneg("replicas", 0));
  if (a.replicas > 8) throw InputError("option --replicas: must be 0..8");
  a.replica_every = static_cast<std::uint32_t>(nonneg("replica-every", 10));
  if (a.replica_every < 1) throw InputError("option --replica-every: must be >= 1");
  a.coarse_every = static_cast<std::uint32_t>(nonneg("coarse-every", a.coarse_every));
  if (parse_coarse_space(args.get_or("coarse-space", "blocks")) == CoarseSpaceKind::kSmoothed) {
    CoarseOptions c;  // the core's defaults, and its ranges (validate)
    auto coarse = [&](const char* flag, int& field) {
      field = static_cast<int>(nonneg(flag, field));
      try {
        c.validate();
      } catch (const InputError& e) {
        throw InputError(std::string("option --") + flag + ": " + e.what());
      }
    };
    coarse("coarse-aggregates", c.aggregates);
    coarse("coarse-smoothing", c.smoothing_steps);
    a.coarse_aggregates = static_cast<std::uint32_t>(c.aggregates);
    a.coarse_smoothing = static_cast<std::uint32_t>(c.smoothing_steps);
  }
  a.refine = args.get_or("refine", a.refine);
  NewtonRefineOptions checked;
  set_refine_mode(checked, a.refine);  // names a value the agents would not know
  a.refine_grad_tol = args.get_double("refine-grad-tol", 0);
  a.refine_rel_tol = args.get_double("refine-rel-tol", 0);
  if (!(a.refine_grad_tol >= 0)) throw InputError("option --refine-grad-tol: must be >= 0");
  if (!(a.refine_rel_tol >= 0)) throw InputError("option --refine-rel-tol: must be >= 0");
  a.refine_sigma = args.get_or("refine-sigma", a.refine_sigma);
  if (!a.refine_sigma.empty()) {
    NewtonRefineOptions check;
    set_sigma_mode(check, a.refine_sigma);
  }
  a.setup_at_once = static_cast<std::uint32_t>(nonneg("setup-at-once", a.setup_at_once));
  if (a.setup_at_once > agent::SetupTurnOptions::kMaxSetupAtOnce)
    throw InputError("option --setup-at-once: must be 0.." +
                     std::to_string(agent::SetupTurnOptions::kMaxSetupAtOnce));
  a.verbose = args.has("verbose");
  a.certify = args.has("certify");
  if (args.has("status-relay") && args.has("no-status-relay"))
    throw InputError("options --status-relay and --no-status-relay exclude each other");
  a.status_relay = !args.has("no-status-relay");
  a.tangent_split_dots = cli::tangent_split_dots_of(args);
  a.robust = cli::parse_robust_options(args);
  a.gnc_known_start = !args.has("gnc-solver-start");
  a.gnc_cluster_probes = static_cast<std::uint32_t>(nonneg("gnc-cluster-probes", 0));
  a.rejected = args.get_or("rejected", "");
  a.reference_cost = args.get_double("reference-cost", 0);
  if (args.has("reference-cost") && !(a.reference_cost > 0 && std::isfinite(a.reference_cost)))
    throw InputError("option --reference-cost: must be a finite number > 0 (the optimal cost f*)");
  if (a.robust.kind != RobustKind::kNone && (a.rejoin_timeout_s > 0 || a.replicas > 0))
    throw InputError(
        "option --robust: a robust run cannot roll back or re-partition; drop --rejoin-timeout "
        "and --replicas");
  return a;
}

transport::SessionOptions coordinator_session_options(const CoordinatorOptions& options) {
  transport::SessionOptions so = options.net.session;
  so.coordinator = true;
  so.num_agents = options.agents;
  so.verbose = options.verbose;
  // A run that survives killed agents talks UDP only (see transport/qos.hpp). The
  // coordinator's participant says so (transport/participant_tags.hpp), and agents started
  // without --udp-only move to UDP only before they announce themselves.
  so.shared_memory = options.rejoin_timeout_s <= 0 && options.replicas == 0;
  return so;
}

}  // namespace tessera::coordinator
