#pragma once
// Minimal, strict command-line parsing shared by all subcommands: `--name value` options,
// `--flag` switches and positional arguments. Unknown or repeated options and missing
// values are InputErrors that name the option, so a typo never passes silently.

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace tessera::cli {

class Arguments {
 public:
  /// `valued` lists options that take a value, `switches` those that do not (names without "--").
  Arguments(const std::vector<std::string>& argv, const std::set<std::string>& valued,
            const std::set<std::string>& switches);

  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const;
  std::optional<std::string> get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  /// Parses the option as a number; throws InputError naming the option if it is not one.
  double get_double(const std::string& name, double fallback) const;
  long get_long(const std::string& name, long fallback) const;
  /// Comma-separated values of the option ("a,b,,c" -> a, b, c); empty when it is absent.
  std::vector<std::string> get_list(const std::string& name) const;

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::set<std::string> switches_set_;
};

}  // namespace tessera::cli
