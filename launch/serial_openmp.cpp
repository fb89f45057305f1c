#include "launch/serial_openmp.hpp"

#include <dlfcn.h>

namespace tessera::launch {

bool serial_openmp() {
  using SetLevels = void (*)(int);
  void* symbol = dlsym(RTLD_DEFAULT, "omp_set_max_active_levels");
  if (!symbol) return false;
  reinterpret_cast<SetLevels>(symbol)(0);
  return true;
}

}  // namespace tessera::launch
