#include "launch/solve_only_flags.hpp"

#include <tessera/util/input_error.hpp>

namespace tessera::launch {

namespace {

// The reasons, shared by the rows they apply to.
constexpr const char* kNotCarried =
    "the coordinator's assignment does not carry it, so every agent would run core's default; "
    "tune it with tessera solve (in process, the same messages as over DDS)";
constexpr const char* kCentralized =
    "it sets the centralized solver, and launch runs the distributed algorithms";
constexpr const char* kCentralizedGnc =
    "it sets the centralized GNC, and launch runs the distributed one (tessera-coordinator "
    "accepts it for tessera solve's option set and changes nothing with it)";
constexpr const char* kInProcessOnly =
    "it is part of tessera solve --online's in-process evaluation, which a run over DDS does "
    "not do";

}  // namespace

const std::vector<SolveOnlyFlag>& solve_only_flags() {
  static const std::vector<SolveOnlyFlag> flags = {
      // Outputs and references of the in-process engine.
      {"trace",
       "the per-round CSV is the in-process engine's; over DDS the coordinator sees progress "
       "digests, not every round (use the summary, --json, and --keep-logs)"},
      {"reference",
       "it runs the centralized solver in the same process; give its optimal cost with "
       "--reference-cost F instead"},
      {"robots",
       "it splits one file into robots for the in-process --init distributed; over DDS every "
       "agent is a robot (--agents, or one robot file per agent)"},
      // The centralized solver's.
      {"stop", kCentralized},
      {"preconditioner", kCentralized},
      {"precond-max-flops", kCentralized},
      {"gnc-inner-iterations", kCentralizedGnc},
      {"gnc-swap-probes", kCentralizedGnc},
      // Two-level rounds: launch's switch is the interval.
      {"coarse", "launch turns the coarse correction on with --coarse-every K (0 = off)"},
      // The in-process engine's tuning that the assignment does not carry.
      {"raw-quaternions", kNotCarried},
      {"max-rank", kNotCarried},
      {"parallel", kNotCarried},
      {"sequential", kNotCarried},
      {"select", kNotCarried},
      {"rel-tol", kNotCarried},
      {"partition-objective", kNotCarried},
      {"partition-file", kNotCarried},
      {"tr-steps", kNotCarried},
      {"tr-grad-reduction", kNotCarried},
      {"irbcd-tr-steps", kNotCarried},
      {"irbcd-grad-reduction", kNotCarried},
      {"tcg-iters", kNotCarried},
      {"tcg-kappa", kNotCarried},
      {"block-precon", kNotCarried},
      {"tangent-refresh", kNotCarried},
      {"tangent-radius", kNotCarried},
      {"restart-c", kNotCarried},
      {"sigma", kNotCarried},
      {"sigma-adapt", kNotCarried},
      {"sigma-fixed", kNotCarried},
      {"sigma-shrink", kNotCarried},
      {"sigma-saturation", kNotCarried},
      {"sigma-theta", kNotCarried},
      {"sigma-min", kNotCarried},
      {"sigma-max", kNotCarried},
      {"irbcd-a0", kNotCarried},
      {"irbcd-class-score", kNotCarried},
      {"irbcd-keep-ab", kNotCarried},
      {"unselected", kNotCarried},
      {"irbcd-n", kNotCarried},
      {"coarse-min-gain", kNotCarried},
      {"certify-grad-tol", kNotCarried},
      {"certify-iters", kNotCarried},
      {"certify-residual", kNotCarried},
      {"certify-precon", kNotCarried},
      {"certify-interface", kNotCarried},
      {"certify-interface-sides", kNotCarried},
      {"refine-cg-iters", kNotCarried},
      {"refine-coarse", kNotCarried},
      {"refine-coarse-form", kNotCarried},
      {"refine-coarse-aggregates", kNotCarried},
      {"refine-interface", kNotCarried},
      {"refine-translation-interface", kNotCarried},
      {"refine-gauge", kNotCarried},
  };
  return flags;
}

const std::vector<SolveOnlyFlag>& online_solve_only_flags() {
  static const std::vector<SolveOnlyFlag> flags = {
      {"real-time",
       "the agents over DDS always run in real time: each epoch absorbs what arrived while "
       "the previous one ran"},
      {"step-every",
       "the agents over DDS step when data has arrived, not on a stream clock of their own"},
      {"robots", "launch --online gives every robot its own agent: --agents N"},
      {"checkpoints", kInProcessOnly},
      {"gap-bound", kInProcessOnly},
      {"until", kInProcessOnly},
      {"baseline", kInProcessOnly},
      {"baseline-every", kInProcessOnly},
      {"baseline-per", kInProcessOnly},
      {"baseline-samples", kInProcessOnly},
      {"baseline-init", kInProcessOnly},
      {"baseline-solver", kInProcessOnly},
      {"no-progress", "launch --online prints no progress lines of its own"},
      {"progress-interval", "launch --online prints no progress lines of its own"},
      {"threads",
       "it runs the in-process agents on that many threads; over DDS each agent is a process"},
  };
  return flags;
}

void refuse_solve_only_flags(const std::vector<std::string>& argv,
                             const std::vector<SolveOnlyFlag>& flags) {
  for (const std::string& token : argv) {
    if (token.rfind("--", 0) != 0) continue;
    const std::string name = token.substr(2, token.find('=') - 2);
    for (const SolveOnlyFlag& f : flags)
      if (name == f.name)
        throw InputError("launch: --" + name + " is an option of `tessera solve` only: " + f.why);
  }
}

}  // namespace tessera::launch
