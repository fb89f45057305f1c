#include <stdexcept>
#include <tessera/problem/objective.hpp>

namespace tessera {

double evaluate_objective(const PoseGraph& graph, const std::vector<Pose>& poses) {
  if (poses.size() != graph.num_poses)
    throw std::invalid_argument("evaluate_objective: one pose per graph pose expected");
  double f = 0.0;
  for (const auto& m : graph.measurements) {
    const Pose& a = poses[m.i];
    const Pose& b = poses[m.j];
    f += m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
  }
  return f;
}

}  // namespace tessera
