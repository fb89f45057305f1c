#include "run_wide_args.hpp"

#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"

namespace tessera::cli {

bool parse_tangent_dots(const std::string& value) {
  if (value == "split") return true;
  if (value == "sequential") return false;
  throw InputError("option --tangent-dots: '" + value + "' is not one of split, sequential");
}

const char* tangent_dots_name(bool split) {
  return split ? "split" : "sequential";
}

bool tangent_split_dots_of(const Arguments& args) {
  return parse_tangent_dots(args.get_or("tangent-dots", tangent_dots_name(true)));
}

bool parse_first_step_factors(const std::string& value) {
  if (value == "grown") return true;
  if (value == "new") return false;
  throw InputError("option --first-step-factors: '" + value + "' is not one of new, grown");
}

const char* first_step_factors_name(bool grown) {
  return grown ? "grown" : "new";
}

bool first_step_on_grown_factors_of(const Arguments& args) {
  return parse_first_step_factors(
      args.get_or("first-step-factors", first_step_factors_name(false)));
}

const char* const kGrowthAndLocalRoundsHelp =
    "  --refactor-growth G a growing block keeps its preconditioner factor, the new poses\n"
    "                      appended to it, until it has G times more poses than it was\n"
    "                      computed for, >= 0 (0: a new factor whenever it gets poses) [0]\n"
    "  --local-threshold F local rounds: a block works and sends its status only while its\n"
    "                      gradient norm is above F * grad-tol / sqrt(blocks), in (0, 1] [1]\n"
    "  --no-local-rounds   every block works and sends its status in every round\n";

void parse_growth_and_local_rounds(const Arguments& args, OnlineOptions& options) {
  options.refactor_growth = args.get_double("refactor-growth", options.refactor_growth);
  if (!(options.refactor_growth >= 0))
    throw InputError("option --refactor-growth: must be a finite number >= 0");
  LocalRoundOptions& local = options.solver.local_rounds;
  local.enabled = !args.has("no-local-rounds");
  local.threshold = args.get_double("local-threshold", local.threshold);
  if (!(local.threshold > 0 && local.threshold <= 1))
    throw InputError("option --local-threshold: must be in (0, 1]");
}

std::string run_wide_disagreement(const RunWideOptions& mine, const RunWideOptions& lead,
                                  unsigned lead_agent) {
  static constexpr const char* kStatuses =
      "it decides which agents send their statuses in each round (agents that differ would "
      "wait for each other)";
  std::string flag, here, there, why;
  if (mine.first_step_on_grown_factors != lead.first_step_on_grown_factors) {
    flag = "--first-step-factors";
    here = first_step_factors_name(mine.first_step_on_grown_factors);
    there = first_step_factors_name(lead.first_step_on_grown_factors);
    why = "it decides which factors precondition every agent's Newton steps";
  } else if (mine.tangent_split_dots != lead.tangent_split_dots) {
    flag = "--tangent-dots";
    here = tangent_dots_name(mine.tangent_split_dots);
    there = tangent_dots_name(lead.tangent_split_dots);
    why = "it changes the last bits of every agent's block updates";
  } else if (mine.local_rounds != lead.local_rounds) {
    flag = "--no-local-rounds";
    here = mine.local_rounds ? "absent" : "given";
    there = lead.local_rounds ? "absent" : "given";
    why = kStatuses;
  } else if (mine.local_rounds && mine.local_threshold != lead.local_threshold) {
    flag = "--local-threshold";
    here = exact_text(mine.local_threshold);
    there = exact_text(lead.local_threshold);
    why = kStatuses;
  } else if (mine.refactor_growth != lead.refactor_growth) {
    flag = "--refactor-growth";
    here = exact_text(mine.refactor_growth);
    there = exact_text(lead.refactor_growth);
    why =
        "it decides when the blocks' preconditioner factors are built again, which changes "
        "every agent's steps";
  } else {
    return "";
  }
  return "option " + flag + ": this agent's " + here + " differs from the lead's (agent " +
         std::to_string(lead_agent) + ") " + there + "; " + why +
         ", so all must be started with the same (tessera launch --online passes its own to "
         "every agent)";
}

}  // namespace tessera::cli
