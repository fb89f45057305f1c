#include "rounding_threads.hpp"

#include <algorithm>
#include <exception>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <thread>

#include "runtime/round_mailbox.hpp"
#include "thread_exchange.hpp"

namespace tessera::agent {

RoundingCase grid_rounding_case(std::size_t poses, int agents, int max_rounds, bool partitioned,
                                std::uint64_t seed) {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kGrid3d;
  g.num_poses = poses;
  g.num_robots = static_cast<std::size_t>(agents);
  g.seed = seed;
  RoundingCase c;
  c.graph = generate_pose_graph(g).graph;
  if (partitioned) {
    PartitionOptions po;
    po.parts = agents;
    po.preset = PartitionPreset::kFast;
    c.assignment = partition_graph(graph_structure_from_pose_graph(c.graph), po).assignment;
  } else {
    for (std::size_t i = 0; i < c.graph.num_poses; ++i)
      c.assignment.push_back(
          static_cast<int>(i * static_cast<std::size_t>(agents) / c.graph.num_poses));
  }
  DistributedOptions o;
  o.max_rounds = max_rounds;
  c.solved = solve_distributed(c.graph, c.assignment, o, c.graph.initial);
  return c;
}

Rounded round_in_threads(const RoundingCase& c, const DistributedRoundingOptions& options,
                         double timeout_s) {
  const PoseGraph& g = c.graph;
  const auto N =
      static_cast<std::uint32_t>(*std::max_element(c.assignment.begin(), c.assignment.end()) + 1);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, c.assignment);
  const int d = g.d;
  test::ThreadExchange ex(N);
  std::vector<RoundLoopResult> out(N);
  std::vector<std::string> errors(N);
  std::vector<std::thread> threads;
  for (std::uint32_t k = 0; k < N; ++k)
    threads.emplace_back([&, k] {
      try {
        AgentLocalData local;
        local.agent_id = k;
        local.num_agents = N;
        local.d = d;
        local.num_poses = g.num_poses;
        for (int b : c.assignment) local.owner.push_back(static_cast<std::uint32_t>(b));
        local.owned = std::vector<std::uint32_t>(layout.poses[k].begin(), layout.poses[k].end());
        for (const Measurement& m : g.measurements)
          if (local.owner[m.i] == k || local.owner[m.j] == k) local.measurements.push_back(m);
        Eigen::MatrixXd Y(c.solved.X.rows(),
                          (d + 1) * static_cast<Eigen::Index>(local.owned.size()));
        for (std::size_t s = 0; s < local.owned.size(); ++s)
          Y.middleCols((d + 1) * static_cast<Eigen::Index>(s), d + 1) =
              c.solved.X.middleCols((d + 1) * static_cast<Eigen::Index>(local.owned[s]), d + 1);
        // The rounding reads only the iterate: no block factor (a 6,000-pose 3D block's
        // took most of a 100,000-pose case's set-up).
        BlockUpdateOptions no_factor;
        no_factor.precondition = false;
        no_factor.max_factor_entries = 1;
        const AgentState state(static_cast<int>(k), d, layout, local.measurements, Y, no_factor);
        test::ThreadChannel ch(ex, k);
        Mailbox mail(ch, timeout_s, k);
        mail.set_num_agents(N);
        RoundLoopResult res;
        res.relaxation_cost = c.solved.relaxation_cost;
        out[k] = DistributedRounding(local, layout, state, mail, options).run(res);
        out[k].rounding_steps = mail.gathers;
      } catch (const std::exception& e) {
        errors[k] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  Rounded r;
  r.poses.resize(g.num_poses);
  for (std::uint32_t k = 0; k < N; ++k) {
    if (!errors[k].empty()) {
      r.errors.push_back("agent " + std::to_string(k) + ": " + errors[k]);
      continue;
    }
    for (std::size_t s = 0; s < layout.poses[k].size(); ++s)
      r.poses[layout.poses[k][s]] = out[k].poses[s];
    if (out[k].cost != out[0].cost ||
        out[k].translation_iterations != out[0].translation_iterations ||
        out[k].rounding_interface_poses != out[0].rounding_interface_poses)
      r.errors.push_back("agent " + std::to_string(k) +
                         " ended with another cost or iteration count");
  }
  if (!r.errors.empty()) return r;
  r.cost = out[0].cost;
  r.iterations = out[0].translation_iterations;
  r.interface_poses = out[0].rounding_interface_poses;
  r.steps = out[0].rounding_steps;
  return r;
}

}  // namespace tessera::agent
