#include "transport/fastdds/process_exit.hpp"

#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace tessera::transport {

void exit_process(int code) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
}

}  // namespace tessera::transport
