#include "commands.hpp"
#include "util/input_error.hpp"

namespace tessera::cli {

int run_generate(const Args&) { throw InputError("'tessera generate' is being built and not available yet"); }

}  // namespace tessera::cli
