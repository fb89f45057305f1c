#pragma once
// `tessera solve` options that `tessera launch` does not take, each with the reason: launch
// refuses them by name with that reason instead of "unknown option", so a user who tuned a
// solve in process learns why the same flag does not reach the agent processes (a flag that
// reaches them is a row of forwarded_flags.hpp, or, online, of online_launch.cpp's list).

#include <string>
#include <vector>

namespace tessera::launch {

/// One refused flag.
struct SolveOnlyFlag {
  const char* name;  ///< `tessera solve`'s flag, without "--"
  const char* why;   ///< why launch does not take it (and what to use instead, if anything)
};

/// The `tessera solve` options a (batch) launch refuses.
const std::vector<SolveOnlyFlag>& solve_only_flags();
/// The `tessera solve --online` options an online launch (`tessera launch --online`) refuses.
const std::vector<SolveOnlyFlag>& online_solve_only_flags();

/// Throws InputError "launch: --NAME is an option of `tessera solve` only: WHY" for the first
/// token of `argv` ("--NAME" or "--NAME=value") that names a row of `flags`; otherwise nothing.
void refuse_solve_only_flags(const std::vector<std::string>& argv,
                             const std::vector<SolveOnlyFlag>& flags);

}  // namespace tessera::launch
