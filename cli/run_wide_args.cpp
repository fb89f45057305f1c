#include "run_wide_args.hpp"

#include <tessera/util/input_error.hpp>

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

std::string run_wide_disagreement(bool mine_grown, bool mine_split, bool lead_grown,
                                  bool lead_split, unsigned lead_agent) {
  std::string flag, here, there, why;
  if (mine_grown != lead_grown) {
    flag = "--first-step-factors";
    here = first_step_factors_name(mine_grown);
    there = first_step_factors_name(lead_grown);
    why = "it decides which factors precondition every agent's Newton steps";
  } else if (mine_split != lead_split) {
    flag = "--tangent-dots";
    here = tangent_dots_name(mine_split);
    there = tangent_dots_name(lead_split);
    why = "it changes the last bits of every agent's block updates";
  } else {
    return "";
  }
  return "option " + flag + ": this agent's " + here + " differs from the lead's (agent " +
         std::to_string(lead_agent) + ") " + there + "; " + why +
         ", so all must be started with the same (tessera launch --online passes its own to "
         "every agent)";
}

}  // namespace tessera::cli
