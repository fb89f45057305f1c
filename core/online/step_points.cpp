#include <limits>
#include <tessera/online/step_points.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>

namespace tessera {

std::vector<StepPointCost> cost_step_points(const PoseGraph& graph,
                                            const std::vector<StepPoint>& points) {
  std::vector<StepPointCost> out;
  out.reserve(points.size());
  for (const StepPoint& p : points)
    out.push_back({p, evaluate_objective(graph, round_solution(graph, p.X))});
  return out;
}

GapLatency gap_latency(const std::vector<StepPointCost>& points, double optimum, double bound,
                       double wait_s) {
  GapLatency g;
  g.wall_s = g.cpu_s = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < points.size(); ++k) {
    const double gap = (points[k].cost - optimum) / optimum;
    g.rel_gaps.push_back(gap);
    if (gap <= bound) {
      if (!g.first) g.first = k;
      if (!g.stays) g.stays = k;
    } else {
      g.stays.reset();
    }
  }
  if (g.first) {
    g.wall_s = wait_s + points[*g.first].wall_s;
    g.cpu_s = wait_s + points[*g.first].cpu_s;
  }
  return g;
}

}  // namespace tessera
