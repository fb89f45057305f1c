#pragma once
// The baseline used by existing distributed PGO systems: each agent keeps a contiguous range of
// pose ids (for a multi-robot file: roughly "its own" trajectory).

#include <cstddef>
#include <vector>

namespace tessera {

/// Splits ids 0..n-1 into `parts` contiguous ranges whose sizes differ by at most one; the first
/// n % parts ranges get the extra vertex (so block b holds ids [b*q + min(b, r), ...)). Requires
/// 1 <= parts <= n (checked by the caller's options).
std::vector<int> sequential_partition(std::size_t n, int parts);

}  // namespace tessera
