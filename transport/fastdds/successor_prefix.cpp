#include "transport/fastdds/successor_prefix.hpp"

#include <cstdint>
#include <random>

namespace tessera::transport {

GuidPrefix successor_prefix(const GuidPrefix& old, bool secured, std::size_t generation) {
  static std::mt19937 random(std::random_device{}());
  GuidPrefix p = old;
  p.value[0] = 0x01;  // eProsima's vendor id
  p.value[1] = 0x0f;
  if (secured)
    for (int k = 2; k < 8; ++k) p.value[k] = static_cast<std::uint8_t>(random());
  p.value[8] = static_cast<std::uint8_t>(0xf0 | (generation & 0x0f));
  for (int k = 9; k < 12; ++k) p.value[k] = static_cast<std::uint8_t>(random());
  return p;
}

}  // namespace tessera::transport
