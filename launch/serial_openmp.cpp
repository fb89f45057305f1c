#include "launch/serial_openmp.hpp"

#include <dlfcn.h>

#include <atomic>

namespace tessera::launch {

namespace {

std::atomic<bool> g_serial{false};

}  // namespace

bool serial_openmp() {
  g_serial.store(true, std::memory_order_relaxed);
  using SetLevels = void (*)(int);
  void* symbol = dlsym(RTLD_DEFAULT, "omp_set_max_active_levels");
  if (!symbol) return false;
  reinterpret_cast<SetLevels>(symbol)(0);
  return true;
}

bool openmp_regions_run_inline() {
  return g_serial.load(std::memory_order_relaxed);
}

}  // namespace tessera::launch

// GCC's entry to a `#pragma omp parallel` region (libgomp's ABI), defined in the executable so
// that CHOLMOD's calls bind here first. After serial_openmp() the region's body runs on the
// calling thread as it is, outside any team: omp_get_num_threads() is 1 and
// omp_get_thread_num() 0 there (libgomp's answers without a team), a worksharing loop's one
// thread takes every iteration and a barrier returns at once, which is what a region of one
// thread does; libgomp's own serialized region also allocated and freed a team each time
// (memalign), ~1,200 instructions a region: 158 M instructions over the 131,931 regions of a
// city10000 run of five agents (in process, callgrind), nearly all in the refinement's block
// factors. Before serial_openmp() (and in every process that never calls
// it) the region goes to libgomp's GOMP_parallel unchanged.
extern "C" __attribute__((visibility("default"))) void GOMP_parallel(void (*fn)(void*), void* data,
                                                                     unsigned num_threads,
                                                                     unsigned flags) {
  if (tessera::launch::openmp_regions_run_inline()) {
    fn(data);
    return;
  }
  using Parallel = void (*)(void (*)(void*), void*, unsigned, unsigned);
  static const Parallel real = reinterpret_cast<Parallel>(dlsym(RTLD_NEXT, "GOMP_parallel"));
  if (real) {
    real(fn, data, num_threads, flags);
  } else {
    fn(data);  // no OpenMP runtime behind this one: a team of one
  }
}
