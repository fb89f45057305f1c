#pragma once
// Two doubles in one vector register (GCC's vector extension: SSE2 on x86-64, plain code
// elsewhere), for the hot kernels that keep their bits by working element-wise: each lane does
// the scalar code's operations in the scalar code's order. Loads and stores go through memcpy,
// so they need no alignment.

#include <cstring>

namespace tessera {

typedef double DoublePair __attribute__((vector_size(16)));

inline DoublePair load_pair(const double* p) {
  DoublePair v;
  std::memcpy(&v, p, sizeof(DoublePair));
  return v;
}

inline void store_pair(double* p, DoublePair v) {
  std::memcpy(p, &v, sizeof(DoublePair));
}

}  // namespace tessera
