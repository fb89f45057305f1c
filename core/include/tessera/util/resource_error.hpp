#pragma once
// The exception type for a resource limit hit while solving: memory (an allocation refused,
// CHOLMOD out of memory) or a size limit (a sparse factor above CHOLMOD's 2^31 entries). Neither
// bad input nor a bug: the same input fits a larger machine or a different method (more agents,
// a distributed solve). Front ends print its message after "out of resources:" and exit 1.

#include <stdexcept>
#include <string>

namespace tessera {

class ResourceError : public std::runtime_error {
 public:
  explicit ResourceError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace tessera
