#include "runtime/partition_step.hpp"

#include <ctime>
#include <tessera/partition/partitioner.hpp>

namespace tessera::coordinator {

namespace {
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}
}  // namespace

PartitionStepResult partition_for_agents(const GraphStructure& graph, std::uint32_t num_agents,
                                         const std::string& preset, std::uint64_t seed,
                                         double time_limit_s) {
  PartitionOptions opt;
  opt.parts = static_cast<int>(num_agents);
  opt.preset = parse_preset_for(preset, graph.num_vertices);
  opt.seed = seed;
  // Agents run IRBCD: fewer colour classes of the block adjacency graph mean more blocks per
  // round and fewer rounds (docs/partitioning.md "Partitions for convergence").
  opt.objective = PartitionObjective::kRounds;
  opt.time_limit_s = time_limit_s;
  opt.validate();
  const double cpu0 = thread_cpu_ms();
  PartitionResult r = partition_graph(graph, opt);
  PartitionStepResult out;
  out.owner.assign(r.assignment.begin(), r.assignment.end());
  out.ms = r.time_ms;
  out.cpu_ms = thread_cpu_ms() - cpu0;
  out.cut_edges = r.metrics.cut_edges;
  return out;
}

}  // namespace tessera::coordinator
