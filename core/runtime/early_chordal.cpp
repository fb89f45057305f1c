#include "runtime/early_chordal.hpp"

#include <tessera/solvers/chordal_initialization.hpp>

namespace tessera::agent {

EarlyChordal::EarlyChordal(const PoseGraph& graph)
    : graph_(graph),
      poses_(std::async(std::launch::async, [&g = graph_] { return chordal_initialization(g); })) {}

EarlyChordal::~EarlyChordal() {
  if (poses_.valid()) poses_.wait();
}

std::optional<std::vector<Pose>> EarlyChordal::take_if_same(const PoseGraph& gathered) {
  if (!poses_.valid()) return std::nullopt;
  std::vector<Pose> poses;
  try {
    poses = poses_.get();
  } catch (...) {
    return std::nullopt;
  }
  if (!same_chordal_problem(graph_, gathered)) return std::nullopt;
  return poses;
}

bool same_chordal_problem(const PoseGraph& a, const PoseGraph& b) {
  if (a.d != b.d || a.num_poses != b.num_poses || a.measurements.size() != b.measurements.size())
    return false;
  for (std::size_t k = 0; k < a.measurements.size(); ++k) {
    const Measurement& x = a.measurements[k];
    const Measurement& y = b.measurements[k];
    if (x.i != y.i || x.j != y.j || x.kappa != y.kappa || x.tau != y.tau) return false;
    if (x.R.rows() != y.R.rows() || x.R.cols() != y.R.cols() || x.t.size() != y.t.size())
      return false;
    if (x.R != y.R || x.t != y.t) return false;
  }
  return true;
}

}  // namespace tessera::agent
