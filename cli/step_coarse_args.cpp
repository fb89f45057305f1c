#include "step_coarse_args.hpp"

#include <tessera/util/input_error.hpp>

namespace tessera::cli {

const char* const kStepCoarseValued[] = {"step-coarse", "step-coarse-min-blocks",
                                         "step-coarse-aggregates", nullptr};

const char* const kStepCoarseHelp =
    "  --step-coarse C     newton: the CG's coarse correction, none (block Jacobi), blocks\n"
    "                      (plus one rigid motion per block of the robots that have met) or\n"
    "                      smoothed (plus the rigid motions of smoothed pieces of each such\n"
    "                      block: the fewest CG iterations once robots have met)  [none]\n"
    "  --step-coarse-min-blocks M  the correction only for groups of at least M linked\n"
    "                      blocks, smaller ones take block Jacobi's steps, >= 2   [3]\n"
    "  --step-coarse-aggregates N|auto  smoothed: pieces per block, 1..64, or auto (one\n"
    "                      per 250 poses of the block, 1..8, chosen again as blocks grow) [8]\n";

const char* step_coarse_name(NewtonRefineOptions::Coarse c) {
  switch (c) {
    case NewtonRefineOptions::Coarse::kBlocks:
      return "blocks";
    case NewtonRefineOptions::Coarse::kSmoothed:
      return "smoothed";
    case NewtonRefineOptions::Coarse::kNone:
      break;
  }
  return "none";
}

NewtonRefineOptions::Coarse coarse_from_flag(const std::string& flag, const std::string& value) {
  for (auto c : {NewtonRefineOptions::Coarse::kNone, NewtonRefineOptions::Coarse::kBlocks,
                 NewtonRefineOptions::Coarse::kSmoothed})
    if (value == step_coarse_name(c)) return c;
  throw InputError("option " + flag + ": '" + value + "' is not one of none, blocks, smoothed");
}

void parse_step_coarse_options(const Arguments& args, OnlineOptions& options) {
  options.newton_coarse = coarse_from_flag("--step-coarse", args.get_or("step-coarse", "none"));
  const long min_blocks = args.get_long("step-coarse-min-blocks", options.newton_coarse_min_blocks);
  if (min_blocks < 2 || min_blocks > 1000000)
    throw InputError("option --step-coarse-min-blocks: must be 2..1000000");
  options.newton_coarse_min_blocks = static_cast<int>(min_blocks);
  const std::string pieces = args.get_or("step-coarse-aggregates", "");
  if (pieces == "auto") {
    options.newton_coarse_aggregates = OnlineOptions::kCoarseAggregatesAuto;
  } else if (!pieces.empty()) {
    const long n = args.get_long("step-coarse-aggregates", options.newton_coarse_aggregates);
    if (n < 1 || n > 64) throw InputError("option --step-coarse-aggregates: must be 1..64 or auto");
    options.newton_coarse_aggregates = static_cast<int>(n);
  }
}

std::string step_coarse_aggregates_name(int aggregates) {
  return aggregates == OnlineOptions::kCoarseAggregatesAuto ? "auto" : std::to_string(aggregates);
}

std::string step_coarse_disagreement(NewtonRefineOptions::Coarse mine, int mine_min_blocks,
                                     int mine_aggregates, NewtonRefineOptions::Coarse lead,
                                     int lead_min_blocks, int lead_aggregates,
                                     unsigned lead_agent) {
  std::string flag, here, there;
  if (mine != lead) {
    flag = "--step-coarse";
    here = step_coarse_name(mine);
    there = step_coarse_name(lead);
  } else if (mine != NewtonRefineOptions::Coarse::kNone && mine_min_blocks != lead_min_blocks) {
    // Without a correction the minimum group changes nothing.
    flag = "--step-coarse-min-blocks";
    here = std::to_string(mine_min_blocks);
    there = std::to_string(lead_min_blocks);
  } else if (mine == NewtonRefineOptions::Coarse::kSmoothed && mine_aggregates != lead_aggregates) {
    // Only the smoothed space has pieces.
    flag = "--step-coarse-aggregates";
    here = step_coarse_aggregates_name(mine_aggregates);
    there = step_coarse_aggregates_name(lead_aggregates);
  } else {
    return "";
  }
  return "option " + flag + ": this agent's " + here + " differs from the lead's (agent " +
         std::to_string(lead_agent) + ") " + there +
         "; the coarse correction adds message steps to every agent's Newton steps, so all must "
         "be started with the same --step-coarse options (tessera launch --online passes its own "
         "to every agent)";
}

}  // namespace tessera::cli
