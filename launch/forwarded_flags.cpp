#include "launch/forwarded_flags.hpp"

#include <cerrno>
#include <cstdlib>
#include <tessera/util/input_error.hpp>

namespace tessera::launch {

namespace {

// A number in [lo, hi], else an InputError naming the flag.
double number_in(const std::string& value, const char* flag, double lo, double hi,
                 const char* range) {
  errno = 0;
  char* end = nullptr;
  const double x = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || errno != 0)
    throw InputError(std::string("option --") + flag + ": '" + value + "' is not a number");
  if (!(x >= lo && x <= hi))
    throw InputError(std::string("launch: --") + flag + " must be in " + range + " seconds");
  return x;
}

void check_status_interval(const std::string& v) {
  number_in(v, "status-interval", 0, 86400, "0..86400");
}

void check_progress_interval(const std::string& v) {
  number_in(v, "progress-interval", 0, 3600, "0..3600");
}

void check_partition_time(const std::string& v) {
  number_in(v, "partition-time", 0, 86400, "0..86400");
}

}  // namespace

const std::vector<ForwardedFlag>& forwarded_flags() {
  static const std::vector<ForwardedFlag> flags = {
      {"out", "output", true, ForwardTo::kCoordinator, "--out FILE",
       "write the merged poses (g2o, VERTEX lines)", nullptr},
      {"tum", "tum", true, ForwardTo::kCoordinator, "--tum FILE", "write the merged poses (TUM)",
       nullptr},
      {"status-interval", "status-interval", true, ForwardTo::kCoordinator, "--status-interval S",
       "coordinator status line (agents alive, rounds, lagging or lost\n"
       "agents) every S seconds and on changes; 0 = off          [5]",
       check_status_interval},
      {"progress-interval", "progress-interval", true, ForwardTo::kCoordinator,
       "--progress-interval S",
       "at most one progress line per S seconds besides the first,\n"
       "the restarts and the last; 0 = every round the coordinator\n"
       "sees (every round with replicas or rejoin)             [0.1]",
       check_progress_interval},
      {"partition-time", "partition-time", true, ForwardTo::kCoordinator, "--partition-time S",
       "cap the partitioner's search at S seconds of wall time; 0 =\n"
       "none, the preset's own effort (with a cap the partition\n"
       "depends on the machine's speed)                           [0]",
       check_partition_time},
  };
  return flags;
}

const ForwardedFlag* find_forwarded_flag(const std::string& name) {
  for (const ForwardedFlag& f : forwarded_flags())
    if (name == f.name) return &f;
  return nullptr;
}

std::string forwarded_flags_help() {
  constexpr std::size_t kTextColumn = 23;  // as the rest of launch's help
  std::string out;
  for (const ForwardedFlag& f : forwarded_flags()) {
    std::string line = std::string("  ") + f.usage;
    // A long usage keeps two blanks before the text, as the rest of the help.
    line += std::string(line.size() + 2 <= kTextColumn ? kTextColumn - line.size() : 2, ' ');
    for (const char* c = f.help; *c; ++c) {
      line += *c;
      if (*c == '\n') line += std::string(kTextColumn, ' ');
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace tessera::launch
