#include <algorithm>
#include <chrono>
#include <cmath>
#include <queue>
#include <tessera/partition/survivor_repartition.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>

namespace tessera {

const char* survivor_strategy_name(SurvivorStrategy s) {
  return s == SurvivorStrategy::kFresh ? "fresh" : "grow";
}

SurvivorStrategy parse_survivor_strategy(const std::string& name) {
  if (name == "grow") return SurvivorStrategy::kGrow;
  if (name == "fresh") return SurvivorStrategy::kFresh;
  throw InputError("survivor re-partition strategy '" + name + "' is not one of grow, fresh");
}

void SurvivorRepartitionOptions::validate() const {
  if (!(eps >= 0.0 && eps <= 1.0))
    throw InputError("SurvivorRepartitionOptions.eps must be in 0..1");
  if (refinement_passes < 0 || refinement_passes > 100)
    throw InputError("SurvivorRepartitionOptions.refinement_passes must be in 0..100");
}

namespace {

constexpr int kUnplaced = -1;

// Edge weight from v to every block among its placed neighbours (dense ids), as (block, weight)
// pairs in first-seen order; `scratch` is a per-block accumulator left zeroed on return.
std::vector<std::pair<int, std::size_t>> connections(const GraphStructure& g, std::size_t v,
                                                     const std::vector<int>& block,
                                                     std::vector<std::size_t>& scratch) {
  std::vector<std::pair<int, std::size_t>> out;
  for (std::size_t e = g.offsets[v]; e < g.offsets[v + 1]; ++e) {
    const int b = block[g.neighbors[e]];
    if (b == kUnplaced) continue;
    if (scratch[static_cast<std::size_t>(b)] == 0) out.emplace_back(b, 0);
    scratch[static_cast<std::size_t>(b)] += g.weights[e];
  }
  for (auto& [b, w] : out) {
    w = scratch[static_cast<std::size_t>(b)];
    scratch[static_cast<std::size_t>(b)] = 0;
  }
  return out;
}

// The block with room that v is most strongly joined to (ties: the smaller block, then the
// lower id), or (kUnplaced, 0) when no placed neighbour's block has room.
std::pair<int, std::size_t> best_block(const std::vector<std::pair<int, std::size_t>>& conn,
                                       const std::vector<std::size_t>& size, std::size_t cap) {
  std::pair<int, std::size_t> best{kUnplaced, 0};
  for (const auto& [b, w] : conn) {
    if (size[static_cast<std::size_t>(b)] >= cap) continue;
    if (best.first == kUnplaced || w > best.second ||
        (w == best.second &&
         std::make_pair(size[static_cast<std::size_t>(b)], b) <
             std::make_pair(size[static_cast<std::size_t>(best.first)], best.first)))
      best = {b, w};
  }
  return best;
}

void grow(const GraphStructure& g, std::vector<int>& block, std::vector<std::size_t>& size,
          std::size_t cap, const std::vector<std::size_t>& lost_vertices, int refinement_passes) {
  const std::size_t S = size.size();
  std::vector<std::size_t> scratch(S, 0);
  // Max-heap of (connection weight, -vertex, block): strongest first, then lowest id. Entries
  // go stale as blocks fill or neighbours get placed; a popped entry is re-checked.
  using Entry = std::tuple<std::size_t, long long, int>;
  std::priority_queue<Entry> heap;
  auto offer = [&](std::size_t v) {
    const auto best = best_block(connections(g, v, block, scratch), size, cap);
    if (best.first != kUnplaced) heap.emplace(best.second, -static_cast<long long>(v), best.first);
  };
  auto place = [&](std::size_t v, int b) {
    block[v] = b;
    ++size[static_cast<std::size_t>(b)];
    for (std::size_t e = g.offsets[v]; e < g.offsets[v + 1]; ++e)
      if (block[g.neighbors[e]] == kUnplaced) offer(g.neighbors[e]);
  };
  for (std::size_t v : lost_vertices) offer(v);
  std::size_t next_seed = 0;  // scan position for lost poses no placed pose reaches
  for (;;) {
    while (!heap.empty()) {
      const auto [w, negv, b] = heap.top();
      heap.pop();
      const std::size_t v = static_cast<std::size_t>(-negv);
      if (block[v] != kUnplaced) continue;
      const auto best = best_block(connections(g, v, block, scratch), size, cap);
      if (best.first == kUnplaced) continue;  // every joined block is full: seeded below
      if (best.first != b || best.second != w) {
        heap.emplace(best.second, negv, best.first);
        continue;
      }
      place(v, b);
    }
    // A lost pose not reachable from any block with room (its component was all lost, or its
    // neighbours' blocks are full): start it in the smallest block (lowest id on ties).
    while (next_seed < lost_vertices.size() && block[lost_vertices[next_seed]] != kUnplaced)
      ++next_seed;
    if (next_seed == lost_vertices.size()) break;
    const int smallest =
        static_cast<int>(std::min_element(size.begin(), size.end()) - size.begin());
    place(lost_vertices[next_seed], smallest);
  }
  // Positive-gain moves of the lost poses only (survivors' poses stay put).
  for (int pass = 0; pass < refinement_passes; ++pass) {
    bool moved = false;
    for (std::size_t v : lost_vertices) {
      const int from = block[v];
      const auto conn = connections(g, v, block, scratch);
      std::size_t own = 0;
      for (const auto& [b, w] : conn)
        if (b == from) own = w;
      int to = from;
      std::size_t best = own;
      for (const auto& [b, w] : conn)
        if (b != from && w > best && size[static_cast<std::size_t>(b)] < cap) {
          to = b;
          best = w;
        }
      if (to == from) continue;
      block[v] = to;
      --size[static_cast<std::size_t>(from)];
      ++size[static_cast<std::size_t>(to)];
      moved = true;
    }
    if (!moved) break;
  }
}

// Fresh multilevel partition for S blocks; new block k goes to the survivor whose old block it
// overlaps most (greedy over the overlap matrix, largest overlap first; ties by ids).
void fresh(const GraphStructure& g, std::vector<int>& block, std::size_t S,
           const std::vector<int>& dense_old, const SurvivorRepartitionOptions& options) {
  PartitionOptions po;
  po.parts = static_cast<int>(S);
  po.preset = options.preset;
  po.eps = options.eps;
  po.seed = options.seed;
  const PartitionResult part = partition_graph(g, po);
  std::vector<std::vector<std::size_t>> overlap(S, std::vector<std::size_t>(S, 0));
  for (std::size_t v = 0; v < g.num_vertices; ++v)
    if (dense_old[v] != kUnplaced)
      ++overlap[static_cast<std::size_t>(part.assignment[v])]
               [static_cast<std::size_t>(dense_old[v])];
  std::vector<std::tuple<std::size_t, long long, long long>> pairs;  // (overlap, -new, -old)
  for (std::size_t k = 0; k < S; ++k)
    for (std::size_t s = 0; s < S; ++s)
      pairs.emplace_back(overlap[k][s], -static_cast<long long>(k), -static_cast<long long>(s));
  std::sort(pairs.rbegin(), pairs.rend());
  std::vector<int> label(S, kUnplaced);
  std::vector<bool> taken(S, false);
  for (const auto& [o, nk, ns] : pairs) {
    const auto k = static_cast<std::size_t>(-nk), s = static_cast<std::size_t>(-ns);
    if (label[k] != kUnplaced || taken[s]) continue;
    label[k] = static_cast<int>(s);
    taken[s] = true;
  }
  for (std::size_t v = 0; v < g.num_vertices; ++v)
    block[v] = label[static_cast<std::size_t>(part.assignment[v])];
}

}  // namespace

SurvivorRepartitionResult repartition_for_survivors(const GraphStructure& graph,
                                                    const std::vector<int>& old_owner,
                                                    int num_agents, const std::vector<int>& lost,
                                                    const SurvivorRepartitionOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  options.validate();
  const std::size_t n = graph.num_vertices;
  if (num_agents < 1) throw InputError("survivor re-partition: num_agents must be >= 1");
  if (old_owner.size() != n)
    throw InputError("survivor re-partition: owner array has " + std::to_string(old_owner.size()) +
                     " entries for " + std::to_string(n) + " poses");
  if (lost.empty()) throw InputError("survivor re-partition: no lost agent given");
  std::vector<bool> is_lost(static_cast<std::size_t>(num_agents), false);
  for (int a : lost) {
    if (a < 0 || a >= num_agents)
      throw InputError("survivor re-partition: lost agent " + std::to_string(a) + " is not in 0.." +
                       std::to_string(num_agents - 1));
    is_lost[static_cast<std::size_t>(a)] = true;
  }
  SurvivorRepartitionResult res;
  std::vector<int> dense_of(static_cast<std::size_t>(num_agents), kUnplaced);
  for (int a = 0; a < num_agents; ++a)
    if (!is_lost[static_cast<std::size_t>(a)]) {
      dense_of[static_cast<std::size_t>(a)] = static_cast<int>(res.survivors.size());
      res.survivors.push_back(a);
    }
  const std::size_t S = res.survivors.size();
  if (S == 0) throw InputError("survivor re-partition: every agent is lost");
  if (S > n) throw InputError("survivor re-partition: more survivors than poses");

  std::vector<int> dense_old(n, kUnplaced);  // survivors' poses keep their block
  std::vector<std::size_t> lost_vertices;
  for (std::size_t v = 0; v < n; ++v) {
    const int o = old_owner[v];
    if (o < 0 || o >= num_agents)
      throw InputError("survivor re-partition: pose " + std::to_string(v) + " has owner " +
                       std::to_string(o) + ", outside 0.." + std::to_string(num_agents - 1));
    dense_old[v] = dense_of[static_cast<std::size_t>(o)];
    if (dense_old[v] == kUnplaced) lost_vertices.push_back(v);
  }
  res.lost_poses = lost_vertices.size();
  res.max_block_size = max_block_size(n, static_cast<int>(S), options.eps);

  res.block = dense_old;
  if (options.strategy == SurvivorStrategy::kGrow) {
    std::vector<std::size_t> size(S, 0);
    for (int b : dense_old)
      if (b != kUnplaced) ++size[static_cast<std::size_t>(b)];
    grow(graph, res.block, size, res.max_block_size, lost_vertices, options.refinement_passes);
  } else {
    fresh(graph, res.block, S, dense_old, options);
  }

  res.owner.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    res.owner[v] = res.survivors[static_cast<std::size_t>(res.block[v])];
    if (res.owner[v] != old_owner[v]) ++res.moved_poses;
  }
  res.metrics = compute_partition_metrics(graph, res.block, static_cast<int>(S));
  res.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace tessera
