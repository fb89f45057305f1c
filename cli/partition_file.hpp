#pragma once
// A partition read from a file: the block of every pose, as `tessera partition --out` writes it
// (one block id per line) or a JSON object with an "assignment" array. Read by `tessera plot
// --partition` and `tessera solve --partition-file`.

#include <cstddef>
#include <string>
#include <vector>

namespace tessera::cli {

/// The block of each of the n poses. Throws InputError (with the file's name) when the file
/// cannot be read, a block is not a non-negative integer, or it lists other than n blocks.
std::vector<int> read_partition(const std::string& path, std::size_t n);

}  // namespace tessera::cli
