#include "robust/gnc_lead_steps.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/pairwise_consistency.hpp>
#include <tessera/robust/tls_weights.hpp>

namespace tessera {

namespace {

// The values in file order, as the in-process engine sees the graph.
PoseGraph in_file_order(GatheredValues& values, const GncAgentInput& in, bool unique) {
  std::sort(values.begin(), values.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  PoseGraph graph;
  graph.d = in.d;
  graph.num_poses = in.num_poses;
  graph.source = in.source;
  graph.measurements.reserve(values.size());
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (unique && k > 0 && values[k].first == values[k - 1].first)
      throw std::runtime_error("robust solve: measurement #" + std::to_string(values[k].first) +
                               " was sent twice");
    graph.measurements.push_back(std::move(values[k].second));
  }
  values.clear();
  return graph;
}

}  // namespace

std::vector<std::uint64_t> inconsistent_closures(GatheredValues& values, const GncAgentInput& in,
                                                 const GncLocalTerms& terms) {
  const PoseGraph graph = in_file_order(values, in, false);
  if (graph.measurements.size() != in.structure.size())
    throw std::runtime_error("robust pcm-gnc: agent 0 has " +
                             std::to_string(graph.measurements.size()) + " of " +
                             std::to_string(in.structure.size()) + " measurements");
  PoseGraph chains = graph;
  chains.measurements.clear();
  for (std::size_t e = 0; e < graph.measurements.size(); ++e)
    if (terms.known()[e]) chains.measurements.push_back(graph.measurements[e]);
  const PairwiseConsistencyResult pcm =
      pairwise_consistency(graph, terms.known(), distributed_initialization(chains, 1), terms.c2());
  return {pcm.inconsistent.begin(), pcm.inconsistent.end()};
}

Eigen::MatrixXd kept_set_start(GatheredValues& values, const GncAgentInput& in,
                               std::size_t rejected, int r, double* cost) {
  const PoseGraph kept = in_file_order(values, in, true);
  if (kept.measurements.size() + rejected != in.structure.size())
    throw std::runtime_error("robust solve: agent 0 has " +
                             std::to_string(kept.measurements.size()) + " kept measurements, not " +
                             std::to_string(in.structure.size() - rejected));
  Eigen::MatrixXd X = lift_poses(initial_poses(kept, in.initialization, in.num_agents), r);
  if (cost) {
    // Each agent's vote sums its own measurements in file order (kept_set_costs); the votes are
    // added in agent-id order.
    const Eigen::Index w = in.d + 1;
    std::vector<double> by_owner(static_cast<std::size_t>(in.num_agents), 0.0);
    for (const Measurement& m : kept.measurements)
      by_owner[static_cast<std::size_t>(weight_owner(m, in.owner))] +=
          lifted_residual_squared(m, X.middleCols(w * static_cast<Eigen::Index>(m.i), w),
                                  X.middleCols(w * static_cast<Eigen::Index>(m.j), w));
    *cost = 0;
    for (double c : by_owner) *cost += c;
  }
  return X;
}

std::vector<std::vector<std::size_t>> cut_neighbours(const GncAgentInput& in) {
  std::vector<std::vector<std::size_t>> nb(static_cast<std::size_t>(in.num_agents));
  for (const auto& [i, j] : in.structure)
    if (in.owner[i] != in.owner[j]) {
      nb[static_cast<std::size_t>(in.owner[i])].push_back(j);
      nb[static_cast<std::size_t>(in.owner[j])].push_back(i);
    }
  for (auto& ids : nb) {
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  }
  return nb;
}

}  // namespace tessera
