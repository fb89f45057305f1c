#include "partition/block_resplit.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <tessera/util/input_error.hpp>

#include "partition/evolution_search.hpp"
#include "partition/evolutionary.hpp"
#include "partition/job_runner.hpp"

namespace tessera::partition_detail {

void BlockResplitOptions::validate() const {
  auto bad = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw InputError("BlockResplitOptions." + field + " = " + value + ": " + rule);
  };
  if (searches < 0 || searches > 8) bad("searches", std::to_string(searches), "must be in 0..8");
  if (population < 2 || population > 64)
    bad("population", std::to_string(population), "must be in 2..64");
  if (!(budget > 0.0 && budget <= 1.0)) bad("budget", std::to_string(budget), "must be in (0, 1]");
  if (!(max_cut_ratio >= 0.0 && max_cut_ratio <= 1.0))
    bad("max_cut_ratio", std::to_string(max_cut_ratio), "must be in 0..1 (0 = no condition)");
  if (kept < 1 || kept > 62) bad("kept", std::to_string(kept), "must be in 1..62");
  if (max_parts < 2 || max_parts > 64)
    bad("max_parts", std::to_string(max_parts), "must be in 2..64");
}

namespace {

// The subgraph induced by the vertices whose `keep` flag is false, and the map from its
// vertices to g's.
struct Induced {
  WorkGraph graph;
  std::vector<int> to_global;
};

Induced induced_subgraph(const WorkGraph& g, const std::vector<int>& part,
                         const std::vector<char>& kept) {
  Induced out;
  std::vector<int> local(static_cast<std::size_t>(g.n), -1);
  for (int v = 0; v < g.n; ++v)
    if (!kept[part[v]]) {
      local[v] = static_cast<int>(out.to_global.size());
      out.to_global.push_back(v);
    }
  WorkGraph& s = out.graph;
  s.n = static_cast<int>(out.to_global.size());
  s.xadj.assign(1, 0);
  for (int v : out.to_global) {
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      if (local[g.adj[e]] >= 0) {
        s.adj.push_back(local[g.adj[e]]);
        s.ew.push_back(g.ew[e]);
      }
    s.xadj.push_back(static_cast<int>(s.adj.size()));
    s.vw.push_back(g.vw[v]);
    s.total_vw += g.vw[v];
  }
  return out;
}

// Cut edges (weights) of each block: the blocks to keep are those most separable already.
std::vector<long long> block_cuts(const WorkGraph& g, const std::vector<int>& part, int k) {
  std::vector<long long> cut(static_cast<std::size_t>(k), 0);
  for (int v = 0; v < g.n; ++v)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      if (part[g.adj[e]] != part[v]) cut[part[v]] += g.ew[e];
  return cut;
}

}  // namespace

BlockResplitResult block_resplit(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                 std::vector<int>& part, const EvolutionParams& params,
                                 const Rng& rng) {
  const BlockResplitOptions& opt = params.resplit;
  opt.validate();
  BlockResplitResult result;
  result.cut = edge_cut(g, part);
  // At most k - 2 blocks kept, so that at least two are split again.
  if (opt.searches == 0 || k > opt.max_parts || k < 3) return result;

  const std::vector<long long> cuts = block_cuts(g, part, k);
  std::vector<int> order(static_cast<std::size_t>(k));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return cuts[a] < cuts[b]; });
  const int kept = std::min(opt.kept, k - 2);
  if (opt.max_cut_ratio > 0.0) {
    // Every kept block's cut against the mean block cut: 2 x cut / k, each cut edge counted
    // by both of its blocks. The blocks are sorted by cut, so the last kept one decides.
    const double mean = 2.0 * static_cast<double>(result.cut) / k;
    if (static_cast<double>(cuts[order[kept - 1]]) > opt.max_cut_ratio * mean) {
      result.detail = "no block clearly separable (" + std::to_string(cuts[order[kept - 1]]) +
                      " cut edges, mean " + std::to_string(std::lround(mean)) + ")";
      return result;
    }
  }

  // The sub-searches' own parameters: the full search's operators with a smaller population
  // and budget, one island, and nothing after the search.
  EvolutionParams sub = params;
  sub.population = opt.population;
  sub.generations = std::max(1, static_cast<int>(std::lround(params.generations * opt.budget)));
  sub.islands = IslandOptions{};
  sub.spectral_seeds = 0;
  sub.polish.rounds = 0;
  sub.resplit.searches = 0;

  Rng seeder = rng;
  const std::uint64_t base = seeder.next() ^ 0xB5297A4D3F84D5B5ULL;
  struct Job {
    int kept = 0;
    Individual best;
    double cpu_ms = 0.0;
  };
  std::vector<Job> jobs;
  for (int j = 0; j < opt.searches; ++j) jobs.push_back(Job{kept, {}, 0.0});

  std::vector<std::function<void()>> work;
  for (std::size_t j = 0; j < jobs.size(); ++j)
    work.emplace_back([&, j] {
      const double c0 = thread_cpu_ms();
      Job& job = jobs[j];
      std::vector<char> kept(static_cast<std::size_t>(k), 0);
      for (int i = 0; i < job.kept; ++i) kept[order[i]] = 1;
      // The blocks searched again, renumbered 0..ks-1.
      std::vector<int> blocks;
      std::vector<long long> sub_ub;
      for (int b = 0; b < k; ++b)
        if (!kept[b]) {
          blocks.push_back(b);
          sub_ub.push_back(ub[b]);
        }
      const int ks = static_cast<int>(blocks.size());
      const Induced induced = induced_subgraph(g, part, kept);
      Rng jrng(base ^ (0x9E3779B97F4A7C15ULL * (j + 1)));
      EvolutionSearch search(induced.graph, ks, sub_ub, sub, jrng);
      search.build_population();
      search.run(INT_MAX);
      Individual merged{part, 0};
      const std::vector<int>& sp = search.best().part;
      for (int v = 0; v < induced.graph.n; ++v) merged.part[induced.to_global[v]] = blocks[sp[v]];
      merged.cut = edge_cut(g, merged.part);
      // The kept blocks' borders may now be improvable as well.
      job.best = vcycle(g, k, ub, std::move(merged), varied(params, jrng), jrng);
      job.cpu_ms = thread_cpu_ms() - c0;
    });
  result.thread_cpu_ms = run_jobs(work, std::min(2, static_cast<int>(work.size())));

  int winner = -1;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    result.detail += (j > 0 ? "; " : "") + std::string("keep ") + std::to_string(jobs[j].kept) +
                     ": " + std::to_string(jobs[j].best.cut) + ", thread cpu " +
                     std::to_string(static_cast<long long>(jobs[j].cpu_ms)) + " ms";
    if (jobs[j].best.cut < result.cut) {
      result.cut = jobs[j].best.cut;
      winner = static_cast<int>(j);
    }
  }
  if (winner >= 0) {
    part = std::move(jobs[static_cast<std::size_t>(winner)].best.part);
    result.improved = true;
  }
  return result;
}

}  // namespace tessera::partition_detail
