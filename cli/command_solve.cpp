#include "commands.hpp"
#include "util/input_error.hpp"

namespace tessera::cli {

int run_solve(const Args&) { throw InputError("'tessera solve' is being built and not available yet"); }

}  // namespace tessera::cli
