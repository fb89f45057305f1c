#include <tessera/partition/sequential_partition.hpp>

namespace tessera {

std::vector<int> sequential_partition(std::size_t n, int parts) {
  std::vector<int> assignment(n, 0);
  if (parts < 1) return assignment;
  const std::size_t p = static_cast<std::size_t>(parts), q = n / p, r = n % p;
  std::size_t v = 0;
  for (std::size_t b = 0; b < p; ++b) {
    const std::size_t size = q + (b < r ? 1 : 0);
    for (std::size_t k = 0; k < size; ++k) assignment[v++] = static_cast<int>(b);
  }
  return assignment;
}

}  // namespace tessera
