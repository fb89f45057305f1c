#include "util/avx_kernels.hpp"

#include <atomic>
#include <cstdlib>

namespace tessera {
namespace {

bool cpu_has_avx() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  return __builtin_cpu_supports("avx");
#else
  return false;
#endif
}

std::atomic<bool>& avx_flag() {
  static std::atomic<bool> flag{cpu_has_avx() && std::getenv("TESSERA_NO_AVX") == nullptr};
  return flag;
}

}  // namespace

bool avx_kernels_enabled() {
  return avx_flag().load(std::memory_order_relaxed);
}

bool set_avx_kernels(bool on) {
  return avx_flag().exchange(on && cpu_has_avx(), std::memory_order_relaxed);
}

}  // namespace tessera
