#include "commands.hpp"
#include "util/input_error.hpp"

namespace tessera::cli {

int run_info(const Args&) { throw InputError("'tessera info' is being built and not available yet"); }

}  // namespace tessera::cli
