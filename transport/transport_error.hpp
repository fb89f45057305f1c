#pragma once
// Failures of the DDS runtime that are not the user's input (entity creation, a write that
// cannot be delivered in time, a malformed message from a peer).

#include <stdexcept>
#include <string>

namespace tessera::transport {

class TransportError : public std::runtime_error {
 public:
  explicit TransportError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace tessera::transport
