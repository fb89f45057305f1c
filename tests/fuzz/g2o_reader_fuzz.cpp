// libFuzzer target for the g2o reader. Any input must either parse into a consistent graph
// or throw InputError naming the file; anything else (crash, sanitizer report, another
// exception type, a hang) is a bug. The istream reader, which goes through a small reused
// buffer here so that lines straddle buffer ends, must agree exactly with the in-memory
// reader. Built by scripts/fuzz_g2o.sh, not by the default build.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/util/input_error.hpp>

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
  // The file's ids: none (0..n-1) or one per pose, strictly increasing; robots for every pose.
  const auto& ids = r.keys.ids;
  check(ids.empty() || ids.size() == g.num_poses);
  for (std::size_t k = 1; k < ids.size(); ++k) check(ids[k - 1] < ids[k]);
  check(r.keys.robot.empty() || r.keys.robot.size() == g.num_poses);
  for (auto robot : r.keys.robot) check(robot < r.keys.num_robots());
  check(!r.keys.fixed || *r.keys.fixed < g.num_poses);
  for (const auto& m : g.measurements) {
    check(m.i < g.num_poses && m.j < g.num_poses && m.i != m.j);
    check(std::isfinite(m.kappa) && m.kappa > 0 && std::isfinite(m.tau) && m.tau > 0);
    check(m.R.rows() == g.d && m.R.cols() == g.d && m.t.size() == g.d);
    check(m.R.allFinite() && m.t.allFinite());
  }
}

bool same(const tessera::G2oReadResult& a, const tessera::G2oReadResult& b) {
  if (a.graph.num_poses != b.graph.num_poses || a.graph.d != b.graph.d ||
      a.graph.measurements.size() != b.graph.measurements.size() ||
      a.graph.initial.size() != b.graph.initial.size() || a.stats.lines != b.stats.lines ||
      a.stats.components != b.stats.components || a.keys.ids != b.keys.ids ||
      a.keys.robot != b.keys.robot || a.keys.fixed != b.keys.fixed)
    return false;
  for (std::size_t k = 0; k < a.graph.measurements.size(); ++k) {
    const auto& x = a.graph.measurements[k];
    const auto& y = b.graph.measurements[k];
    if (x.i != y.i || x.j != y.j || x.kappa != y.kappa || x.tau != y.tau || x.t != y.t ||
        x.R != y.R)
      return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  tessera::G2oReadOptions options;
  options.allow_disconnected = size % 2 == 1;
  options.normalize_quaternions = size % 3 != 0;

  tessera::G2oReadResult from_text;
  std::string text_error;
  try {
    from_text = tessera::read_g2o_text(text, "fuzz.g2o", options);
    check_graph(from_text);
  } catch (const tessera::InputError& e) {
    text_error = e.what();
    check(text_error.rfind("fuzz.g2o", 0) == 0);
  }

  options.read_chunk_bytes = 1 + (size > 0 ? data[0] % 17 : 0);
  std::istringstream in(text);
  try {
    const auto from_stream = tessera::read_g2o_stream(in, "fuzz.g2o", options);
    check(text_error.empty() && same(from_text, from_stream));
  } catch (const tessera::InputError& e) {
    check(text_error == e.what());
  }
  return 0;
}
