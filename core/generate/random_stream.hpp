#pragma once
// Deterministic random numbers for the generator. std::*_distribution output differs between
// standard libraries, so uniform and normal variates are derived here from the raw
// std::mt19937_64 bits (whose sequence the standard fixes): same seed, same graph, everywhere.

#include <cstdint>
#include <random>

namespace tessera {

class RandomStream {
 public:
  /// Stream number `stream` of `seed`: independent streams let one part of the generator
  /// (e.g. noise) draw more or fewer numbers without changing another (e.g. closures).
  RandomStream(std::uint64_t seed, std::uint64_t stream);

  /// Uniform in [0, 1), 53 random bits.
  double uniform();
  /// Uniform integer in [0, bound), bound > 0.
  std::uint64_t below(std::uint64_t bound);
  /// Standard normal (Box-Muller; the second variate of each pair is kept for the next call).
  double normal();

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace tessera
