#pragma once
// The one exception type for bad user input (files, flags, options). Its message always
// says where the problem is (file and line when there is one) and what is wrong, so a
// front end can print it as is and exit non-zero.

#include <cstddef>
#include <stdexcept>
#include <string>

namespace tessera {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
  /// "file:line: what" (line 0 means the file as a whole: "file: what").
  InputError(const std::string& file, std::size_t line, const std::string& what)
      : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                           what) {}
};

}  // namespace tessera
