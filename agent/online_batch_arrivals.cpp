#include "agent/online_batch_arrivals.hpp"

#include <algorithm>
#include <iterator>

namespace tessera::agent {

void BatchArrivals::arrived(std::uint32_t robot, std::uint64_t sequence, double at_s) {
  arrived_at_.emplace(std::make_pair(robot, sequence), at_s);
}

double BatchArrivals::absorbed(const GraphStream& graph, double solved_at_s, double step_start_s,
                               std::vector<double>& latencies, double step_cpu_s,
                               std::vector<double>* cpu_latencies) {
  double oldest = step_start_s;
  for (const auto& [key, t] : arrived_at_)
    if (key.second < graph.absorbed_batches(key.first)) {
      latencies.push_back(solved_at_s - t);
      if (cpu_latencies) cpu_latencies->push_back(std::max(0.0, step_start_s - t) + step_cpu_s);
      oldest = std::min(oldest, t);
    }
  for (auto it = arrived_at_.begin(); it != arrived_at_.end();)
    it = it->first.second < graph.absorbed_batches(it->first.first) ? arrived_at_.erase(it)
                                                                    : std::next(it);
  return oldest;
}

}  // namespace tessera::agent
