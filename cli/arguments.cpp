#include "arguments.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <tessera/util/input_error.hpp>

namespace tessera::cli {

Arguments::Arguments(const std::vector<std::string>& argv, const std::set<std::string>& valued,
                     const std::set<std::string>& switches) {
  for (std::size_t k = 0; k < argv.size(); ++k) {
    const std::string& a = argv[k];
    if (a.size() > 2 && a.compare(0, 2, "--") == 0) {
      std::string name = a.substr(2);
      std::string value;
      bool inline_value = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inline_value = true;
      }
      if (switches.count(name)) {
        if (inline_value) throw InputError("option --" + name + " takes no value");
        switches_set_.insert(name);
      } else if (valued.count(name)) {
        if (!inline_value) {
          if (k + 1 >= argv.size()) throw InputError("option --" + name + " needs a value");
          value = argv[++k];
        }
        if (values_.count(name)) throw InputError("option --" + name + " given twice");
        values_[name] = value;
      } else {
        throw InputError("unknown option --" + name + " (see --help)");
      }
    } else {
      positional_.push_back(a);
    }
  }
}

bool Arguments::has(const std::string& name) const {
  return switches_set_.count(name) > 0 || values_.count(name) > 0;
}

std::optional<std::string> Arguments::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Arguments::get_or(const std::string& name, const std::string& fallback) const {
  auto v = get(name);
  return v ? *v : fallback;
}

double Arguments::get_double(const std::string& name, double fallback) const {
  auto v = get(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  double x = std::strtod(v->c_str(), &end);
  if (v->empty() || *end != '\0' || errno != 0 || !std::isfinite(x))
    throw InputError("option --" + name + ": '" + *v + "' is not a finite number");
  return x;
}

long Arguments::get_long(const std::string& name, long fallback) const {
  auto v = get(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  long x = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || *end != '\0' || errno != 0)
    throw InputError("option --" + name + ": '" + *v + "' is not an integer");
  return x;
}

std::vector<std::string> Arguments::get_list(const std::string& name) const {
  std::vector<std::string> out;
  const std::string s = get_or(name, "");
  std::size_t start = 0;
  while (start < s.size()) {
    std::size_t comma = s.find(',', start);
    if (comma == std::string::npos) comma = s.size();
    if (comma > start) out.push_back(s.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

}  // namespace tessera::cli
