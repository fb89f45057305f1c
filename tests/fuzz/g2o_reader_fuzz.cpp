// libFuzzer target for the g2o reader (istream variant). Any input must either parse into a
// consistent graph or throw InputError; anything else (crash, sanitizer report, another
// exception type, a hang) is a bug. Built by scripts/fuzz_g2o.sh, not by the default build.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "io/g2o_reader.hpp"
#include "util/input_error.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();  // libFuzzer reports the input that broke an invariant
}

void check_graph(const tessera::G2oReadResult& r) {
  const auto& g = r.graph;
  check(g.d == 2 || g.d == 3);
  check(g.num_poses > 0 && !g.measurements.empty());
  check(g.initial.empty() || g.initial.size() == g.num_poses);
  check(r.stats.parallel_edges + r.stats.distinct_pairs == g.measurements.size());
  for (const auto& m : g.measurements) {
    check(m.i < g.num_poses && m.j < g.num_poses && m.i != m.j);
    check(std::isfinite(m.kappa) && m.kappa > 0 && std::isfinite(m.tau) && m.tau > 0);
    check(m.R.rows() == g.d && m.R.cols() == g.d && m.t.size() == g.d);
    check(m.R.allFinite() && m.t.allFinite());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (bool allow_disconnected : {false, true}) {
    tessera::G2oReadOptions options;
    options.allow_disconnected = allow_disconnected;
    options.normalize_quaternions = !allow_disconnected;
    std::istringstream in(text);
    try {
      check_graph(tessera::read_g2o_stream(in, "fuzz.g2o", options));
    } catch (const tessera::InputError& e) {
      check(std::string(e.what()).rfind("fuzz.g2o", 0) == 0);
    }
  }
  return 0;
}
