#include "partition/partitioner.hpp"

#include <chrono>
#include <cmath>

#include "partition/evolutionary.hpp"
#include "partition/multilevel.hpp"
#include "partition/sequential_partition.hpp"
#include "util/input_error.hpp"

namespace tessera {

using namespace partition_detail;

const char* preset_name(PartitionPreset preset) {
  switch (preset) {
    case PartitionPreset::kSequential:
      return "sequential";
    case PartitionPreset::kFast:
      return "fast";
    case PartitionPreset::kEco:
      return "eco";
    case PartitionPreset::kStrong:
      return "strong";
    case PartitionPreset::kHighest:
      return "highest";
  }
  return "?";
}

PartitionPreset parse_preset(const std::string& name) {
  for (auto p : {PartitionPreset::kSequential, PartitionPreset::kFast, PartitionPreset::kEco,
                 PartitionPreset::kStrong, PartitionPreset::kHighest})
    if (name == preset_name(p)) return p;
  throw InputError("unknown preset '" + name + "' (valid: sequential, fast, eco, strong, highest)");
}

void PartitionOptions::validate() const {
  if (parts < 1 || parts > 64)
    throw InputError("PartitionOptions.parts = " + std::to_string(parts) + ": must be in 1..64");
  if (!std::isfinite(eps) || eps < 0.0 || eps > 1.0)
    throw InputError("PartitionOptions.eps = " + std::to_string(eps) + ": must be in 0..1");
}

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Per-preset effort. Coarse vertices stay light enough that the coarsest graph can still be
// balanced well; the coarsest graph has a few dozen vertices per block.
CycleParams cycle_params(PartitionPreset preset, const WorkGraph& g, int k, long long lmax) {
  CycleParams cp;
  cp.coarsening.stop_vertices = std::max(20 * k, 80);
  cp.coarsening.max_vertex_weight = static_cast<int>(std::max<long long>(1, lmax / 10));
  (void)g;
  switch (preset) {
    case PartitionPreset::kFast:
      cp.initial.repeats = 2;
      cp.initial.bisection_tries = 3;
      cp.fm = {2, 40};
      break;
    case PartitionPreset::kEco:
      cp.initial.repeats = 3;
      cp.initial.bisection_tries = 4;
      cp.fm = {3, 100};
      break;
    default:
      cp.initial.repeats = 4;
      cp.initial.bisection_tries = 6;
      cp.fm = {4, 200};
      break;
  }
  cp.initial.fm = cp.fm;
  return cp;
}

}  // namespace

PartitionResult partition_graph(const GraphStructure& graph, const PartitionOptions& options) {
  options.validate();
  const std::size_t n = graph.num_vertices;
  if (static_cast<std::size_t>(options.parts) > n)
    throw InputError(graph.source, 0,
                     "cannot split " + std::to_string(n) + " vertices into " +
                         std::to_string(options.parts) + " non-empty blocks (--parts > poses)");
  const int k = options.parts;
  PartitionResult result;
  result.max_block_size = max_block_size(n, k, options.eps);
  const auto t0 = Clock::now();
  auto phase = [&](const std::string& name, const std::string& detail, long long cut,
                   Clock::time_point since) {
    result.trace.push_back({name, detail, cut, ms_since(since)});
  };

  if (options.preset == PartitionPreset::kSequential || k == 1) {
    result.assignment = sequential_partition(n, k);
    result.time_ms = ms_since(t0);
    result.metrics = compute_partition_metrics(graph, result.assignment, k);
    phase("sequential", std::to_string(k) + " contiguous id ranges",
          static_cast<long long>(result.metrics.cut_edges), t0);
    return result;
  }

  const WorkGraph g = to_work_graph(graph);
  const long long lmax = static_cast<long long>(result.max_block_size);
  const std::vector<long long> ub(static_cast<std::size_t>(k), lmax);
  const CycleParams cp = cycle_params(options.preset, g, k, lmax);
  Rng rng(options.seed);
  std::vector<int> part;

  auto describe = [](const CycleStats& s) {
    return std::to_string(s.levels) + " levels, coarsest " + std::to_string(s.coarsest_vertices) +
           " vertices (cut " + std::to_string(s.coarsest_cut) + ")";
  };
  auto vcycles = [&](int count) {
    for (int c = 0; c < count; ++c) {
      const auto tc = Clock::now();
      CycleStats s;
      std::vector<int> p = guided_cycle(g, k, ub, part, part, cp, rng, &s);
      if (s.cut <= edge_cut(g, part)) part.swap(p);
      phase("v-cycle", describe(s), edge_cut(g, part), tc);
    }
  };

  switch (options.preset) {
    case PartitionPreset::kFast:
    case PartitionPreset::kEco: {
      const bool eco = options.preset == PartitionPreset::kEco;
      const int runs = eco ? 3 : 1;
      long long best = -1;
      for (int r = 0; r < runs; ++r) {
        const auto tr = Clock::now();
        CycleStats s;
        std::vector<int> p = multilevel_partition(g, k, ub, cp, rng, &s);
        if (best < 0 || s.cut < best) {
          best = s.cut;
          part.swap(p);
        }
        phase("multilevel", describe(s), best, tr);
      }
      vcycles(eco ? 3 : 1);
      break;
    }
    case PartitionPreset::kStrong:
    case PartitionPreset::kHighest: {
      EvolutionParams ep;
      ep.cycle = cp;
      if (options.preset == PartitionPreset::kStrong) {
        ep.population = 4;
        ep.vcycles = 1;
        ep.generations = 12;
      } else {
        ep.population = 10;
        ep.vcycles = 2;
        ep.generations = 150;
      }
      auto tp = Clock::now();
      part = evolve(g, k, ub, ep, rng,
                    [&](const std::string& name, const std::string& detail, long long cut) {
                      phase(name, detail, cut, tp);
                      tp = Clock::now();
                    });
      break;
    }
    default:
      break;
  }
  rebalance(g, k, part, ub);  // no-op for balanced results; a safety net for the promise above
  result.assignment = std::move(part);
  result.time_ms = ms_since(t0);
  result.metrics = compute_partition_metrics(graph, result.assignment, k);
  return result;
}

}  // namespace tessera
