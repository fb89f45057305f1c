#pragma once
// A small JSON object writer for the CLI's summaries (one flat object of keys in insertion
// order; values are numbers, strings, booleans, null, arrays of numbers, strings or objects,
// and nested objects).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tessera::cli {

class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, long long value);
  JsonObject& add(const std::string& key, int value) {
    return add(key, static_cast<long long>(value));
  }
  JsonObject& add(const std::string& key, long value) {
    return add(key, static_cast<long long>(value));
  }
  JsonObject& add(const std::string& key, std::size_t value) {
    return add(key, static_cast<long long>(value));
  }
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) {
    return add(key, std::string(value));
  }
  JsonObject& add(const std::string& key, const std::optional<bool>& value);
  JsonObject& add(const std::string& key, const std::optional<double>& value);
  JsonObject& add(const std::string& key, const std::vector<double>& values);
  JsonObject& add(const std::string& key, const std::vector<std::size_t>& values);
  JsonObject& add(const std::string& key, const std::vector<std::string>& values);
  JsonObject& add(const std::string& key, const JsonObject& nested);
  /// An array of objects, one per line.
  JsonObject& add(const std::string& key, const std::vector<JsonObject>& objects);
  JsonObject& add_null(const std::string& key);

  /// Pretty-printed text with a trailing newline.
  std::string str(int indent = 0) const;
  /// The object on one line, no trailing newline.
  std::string compact() const;

 private:
  std::vector<std::pair<std::string, std::string>> fields_;  // key, encoded value
};

/// JSON string literal (quotes and escapes included).
std::string json_quote(const std::string& s);
/// Shortest round-trip decimal form of a finite double; non-finite values become null.
std::string json_number(double x);

/// Writes text to `path`, or to stdout when path is "-". Throws InputError if it cannot.
void write_output(const std::string& path, const std::string& text);

}  // namespace tessera::cli
