#include "commands.hpp"
#include "util/input_error.hpp"

namespace tessera::cli {

int run_partition(const Args&) { throw InputError("'tessera partition' is being built and not available yet"); }

}  // namespace tessera::cli
