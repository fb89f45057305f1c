#pragma once
// The one switch between a hot kernel's AVX build and its SSE2 one. The project is built for
// baseline x86-64 (SSE2); a few kernels also have a copy compiled for AVX (function-level
// target attribute, never FMA: a fused multiply-add rounds once and would change the bits)
// and pick it at run time here. Both copies compute the same operations in the same order, so
// the results are the same bits either way.
//
// TESSERA_AVX_KERNELS is defined where the AVX copies can be compiled at all (GCC-compatible
// compilers on x86-64); the kernels' files build those copies only under it.

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define TESSERA_AVX_KERNELS 1
#endif

namespace tessera {

/// True when the AVX kernels run: the CPU and OS support AVX and TESSERA_NO_AVX is unset (read
/// once), unless set_avx_kernels(false) switched them off.
bool avx_kernels_enabled();

/// Switches the AVX kernels off (false) or back on (true; only where the CPU has AVX), for
/// tests that check both copies. Returns the previous state. Not for use while kernels run.
bool set_avx_kernels(bool on);

}  // namespace tessera
