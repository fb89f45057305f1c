#include "rebalance_args.hpp"

#include <cmath>
#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"

namespace tessera::cli {

const char* const kRebalanceValued[] = {"cut-fraction", "block-slack",  "block-min-excess",
                                        "cut-passes",   "cut-patience", nullptr};
const char* const kRebalanceSwitches[] = {"no-place-by-links", "no-rebalance", nullptr};

const char* const kRebalanceHelp =
    "  --cut-fraction F    re-partition: refine the blocks' border when more than F of the\n"
    "                      measurements join two blocks, in [0, 1]; 1 = robot blocks  [0.02]\n"
    "  --block-slack S     blocks stay within (1 + S) ceil(n/N) + K poses (K: --block-min-excess)\n"
    "                      and, with the refinement on, above (1 - S) floor(n/N), S >= 0 [0.2]\n"
    "  --block-min-excess K  poses over (1 + S) ceil(n/N) before any moves out, >= 0   [10]\n"
    "  --cut-passes P      refinement passes at most, >= 1                            [8]\n"
    "  --cut-patience K    a pass stops after K moves without a better cut, >= 1      [64]\n"
    "  --no-place-by-links new poses join their robot's block, not the block holding most\n"
    "                      of their measurements\n"
    "  --no-rebalance      blocks stay the robots' (no move at all)\n";

RebalanceOptions parse_rebalance_options(const Arguments& args) {
  RebalanceOptions o;
  o.cut_fraction = args.get_double("cut-fraction", o.cut_fraction);
  if (!(o.cut_fraction >= 0 && o.cut_fraction <= 1))
    throw InputError("option --cut-fraction: must be in [0, 1] (1 = no cut refinement)");
  o.slack = args.get_double("block-slack", o.slack);
  if (!(o.slack >= 0) || !std::isfinite(o.slack))
    throw InputError("option --block-slack: must be a finite number >= 0");
  const long excess = args.get_long("block-min-excess", static_cast<long>(o.min_excess));
  if (excess < 0) throw InputError("option --block-min-excess: must be >= 0");
  o.min_excess = static_cast<std::size_t>(excess);
  const long passes = args.get_long("cut-passes", o.max_passes);
  if (passes < 1 || passes > 1000000) throw InputError("option --cut-passes: must be 1..1000000");
  o.max_passes = static_cast<int>(passes);
  const long patience = args.get_long("cut-patience", static_cast<long>(o.pass_patience));
  if (patience < 1) throw InputError("option --cut-patience: must be >= 1");
  o.pass_patience = static_cast<std::size_t>(patience);
  o.place_by_links = !args.has("no-place-by-links");
  o.enabled = !args.has("no-rebalance");
  o.validate();
  return o;
}

std::string rebalance_disagreement(const RebalanceOptions& mine, const RebalanceOptions& lead,
                                   unsigned lead_agent) {
  std::string flag, here, there;
  if (mine.enabled != lead.enabled) {
    flag = "--no-rebalance";
    here = mine.enabled ? "absent" : "given";
    there = lead.enabled ? "absent" : "given";
  } else if (mine.cut_fraction != lead.cut_fraction) {
    flag = "--cut-fraction";
    here = exact_text(mine.cut_fraction);
    there = exact_text(lead.cut_fraction);
  } else if (mine.slack != lead.slack) {
    flag = "--block-slack";
    here = exact_text(mine.slack);
    there = exact_text(lead.slack);
  } else if (mine.min_excess != lead.min_excess) {
    flag = "--block-min-excess";
    here = std::to_string(mine.min_excess);
    there = std::to_string(lead.min_excess);
  } else if (mine.max_passes != lead.max_passes) {
    flag = "--cut-passes";
    here = std::to_string(mine.max_passes);
    there = std::to_string(lead.max_passes);
  } else if (mine.pass_patience != lead.pass_patience) {
    flag = "--cut-patience";
    here = std::to_string(mine.pass_patience);
    there = std::to_string(lead.pass_patience);
  } else if (mine.place_by_links != lead.place_by_links) {
    flag = "--no-place-by-links";
    here = mine.place_by_links ? "absent" : "given";
    there = lead.place_by_links ? "absent" : "given";
  } else {
    return "";
  }
  return "option " + flag + ": this agent's " + here + " differs from the lead's (agent " +
         std::to_string(lead_agent) + ") " + there +
         "; every agent of an online run moves the blocks itself, so all must be started with "
         "the same re-partition options (tessera launch --online passes its own to every agent)";
}

}  // namespace tessera::cli
