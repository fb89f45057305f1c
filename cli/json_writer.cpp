#include "json_writer.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <tessera/util/input_error.hpp>

namespace tessera::cli {

std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  // The shortest of 15..17 significant digits that reads back as the same double.
  char buf[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

JsonObject& JsonObject::add(const std::string& key, double value) {
  fields_.emplace_back(key, json_number(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, long long value) {
  fields_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, bool value) {
  fields_.emplace_back(key, value ? "true" : "false");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  fields_.emplace_back(key, json_quote(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::optional<bool>& value) {
  return value ? add(key, *value) : add_null(key);
}
JsonObject& JsonObject::add(const std::string& key, const std::optional<double>& value) {
  return value ? add(key, *value) : add_null(key);
}
JsonObject& JsonObject::add(const std::string& key, const std::vector<double>& values) {
  std::string s = "[";
  for (std::size_t k = 0; k < values.size(); ++k) s += (k ? ", " : "") + json_number(values[k]);
  fields_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::vector<std::size_t>& values) {
  std::string s = "[";
  for (std::size_t k = 0; k < values.size(); ++k) s += (k ? ", " : "") + std::to_string(values[k]);
  fields_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::vector<std::string>& values) {
  std::string s = "[";
  for (std::size_t k = 0; k < values.size(); ++k) s += (k ? ", " : "") + json_quote(values[k]);
  fields_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::vector<JsonObject>& objects) {
  if (objects.empty()) {
    fields_.emplace_back(key, "[]");
    return *this;
  }
  std::string s = "[";
  for (std::size_t k = 0; k < objects.size(); ++k)
    s += std::string(k ? "," : "") + "\n    " + objects[k].compact();
  fields_.emplace_back(key, s + "\n  ]");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const JsonObject& nested) {
  std::string text = nested.str(1);
  text.pop_back();  // nested objects end without the newline
  fields_.emplace_back(key, text);
  return *this;
}
JsonObject& JsonObject::add_null(const std::string& key) {
  fields_.emplace_back(key, "null");
  return *this;
}

std::string JsonObject::str(int indent) const {
  const std::string pad(static_cast<std::size_t>(2 * (indent + 1)), ' ');
  std::string out = "{\n";
  for (std::size_t k = 0; k < fields_.size(); ++k) {
    out += pad + json_quote(fields_[k].first) + ": " + fields_[k].second;
    out += k + 1 < fields_.size() ? ",\n" : "\n";
  }
  out += std::string(static_cast<std::size_t>(2 * indent), ' ') + "}\n";
  return out;
}

std::string JsonObject::compact() const {
  std::string out = "{";
  for (std::size_t k = 0; k < fields_.size(); ++k)
    out += (k ? ", " : "") + json_quote(fields_[k].first) + ": " + fields_[k].second;
  return out + "}";
}

void write_output(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text << std::flush;
    return;
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path, 0, "cannot open for writing");
  out << text;
  if (!out.flush()) throw InputError(path, 0, "write failed");
}

}  // namespace tessera::cli
