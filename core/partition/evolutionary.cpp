#include "partition/evolutionary.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "partition/light_block.hpp"
#include "util/input_error.hpp"

namespace tessera::partition_detail {

void EvolutionParams::validate() const {
  auto bad = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw InputError("EvolutionParams." + field + " = " + value + ": " + rule);
  };
  auto share = [&](const char* field, double v) {
    if (!std::isfinite(v) || v < 0.0 || v > 1.0) bad(field, std::to_string(v), "must be in 0..1");
  };
  if (population < 1) bad("population", std::to_string(population), "must be >= 1");
  if (vcycles < 0) bad("vcycles", std::to_string(vcycles), "must be >= 0");
  if (generations < 0) bad("generations", std::to_string(generations), "must be >= 0");
  if (stall_limit < 1) bad("stall_limit", std::to_string(stall_limit), "must be >= 1");
  share("mutation_rate", mutation_rate);
  share("matching_share", matching_share);
  share("cross_share", cross_share);
  share("light_share", light_share);
  share("light_cycle_share", light_cycle_share);
  if (light_tail < 0) bad("light_tail", std::to_string(light_tail), "must be >= 0");
  if (spectral_seeds < 0) bad("spectral_seeds", std::to_string(spectral_seeds), "must be >= 0");
  if (!std::isfinite(spectral_gap) || spectral_gap < 0.0)
    bad("spectral_gap", std::to_string(spectral_gap), "must be >= 0");
  polish.validate();
  spectral.validate();
}

namespace {

struct Individual {
  std::vector<int> part;
  long long cut = 0;
};

// One label per (block in a, block in b); b has kb blocks.
std::vector<int> pair_label(const std::vector<int>& a, const std::vector<int>& b, int kb) {
  std::vector<int> label(a.size());
  for (std::size_t v = 0; v < a.size(); ++v) label[v] = a[v] * kb + b[v];
  return label;
}

// Improves `p` by V-cycles that keep its blocks contractible.
Individual vcycle(const WorkGraph& g, int k, const std::vector<long long>& ub, Individual ind,
                  const CycleParams& cp, Rng& rng) {
  std::vector<int> p = guided_cycle(g, k, ub, ind.part, ind.part, cp, rng);
  const long long cut = edge_cut(g, p);
  if (cut <= ind.cut) return {std::move(p), cut};
  return ind;
}

Individual combine(const WorkGraph& g, int k, const std::vector<long long>& ub, const Individual& a,
                   const Individual& b, const CycleParams& cp, Rng& rng) {
  const Individual& better = a.cut <= b.cut ? a : b;
  std::vector<int> p = guided_cycle(g, k, ub, pair_label(a.part, b.part, k), better.part, cp, rng);
  const long long cut = edge_cut(g, p);
  if (cut <= better.cut) return {std::move(p), cut};
  return better;
}

// KaFFPaE's cross combine: a fresh partition into a different number of blocks kx (drawn from
// [k/2, 4k]) with a looser balance has its boundaries in other places than any k-way partition;
// contracting only vertices that `a` and it put together lets the V-cycle on `a` move whole
// regions along those boundaries. The result is never worse than `a`.
Individual cross_combine(const WorkGraph& g, int k, const std::vector<long long>& ub,
                         const Individual& a, const CycleParams& cp, Rng& rng) {
  const int kx = std::max(2, k / 2 + rng.below(4 * k - k / 2 + 1));
  const double eps = 0.03 + 0.2 * rng.uniform();
  const long long avg = (g.total_vw + kx - 1) / kx;
  const std::vector<long long> ubx(static_cast<std::size_t>(kx),
                                   static_cast<long long>((1.0 + eps) * static_cast<double>(avg)));
  CycleParams fresh_cp = cp;
  // Only its boundaries matter, not their last few edges: a cheap run (no flows, short FM)
  // keeps the many-block partitions from dominating the search's cost.
  fresh_cp.use_flow = false;
  fresh_cp.fm.max_passes = 2;
  fresh_cp.fm.stop_after = 60;
  fresh_cp.initial.repeats = 2;
  fresh_cp.initial.fm = fresh_cp.fm;
  fresh_cp.coarsening.stop_vertices = std::max(cp.coarsening.stop_vertices, 20 * kx);
  fresh_cp.coarsening.max_vertex_weight =
      std::max(2, static_cast<int>(std::min<long long>(cp.coarsening.max_vertex_weight, avg / 30)));
  const std::vector<int> other = multilevel_partition(g, kx, ubx, fresh_cp, rng);
  std::vector<int> p = guided_cycle(g, k, ub, pair_label(a.part, other, kx), a.part, cp, rng);
  const long long cut = edge_cut(g, p);
  if (cut <= a.cut) return {std::move(p), cut};
  return a;
}

// Every operation draws its flow corridor size from {alpha, 2 alpha} and its coarsening (label
// propagation or, with probability matching_share, heavy-edge matching): no single choice is
// best on all benchmark graphs (matching finds the best cuts on rim and parking-garage, label
// propagation on city10000), and mixing them diversifies the population.
CycleParams varied(const EvolutionParams& params, Rng& rng) {
  CycleParams c = params.cycle;
  if (rng.next() & 1) c.flow.alpha *= 2;
  if (params.matching_share > 0.0 && rng.uniform() < params.matching_share) {
    c.coarsening.label_propagation_rounds = 0;
    // Matching only halves each level, so its finer levels are much larger than label
    // propagation's: flows there would cost several times more for little gain.
    c.flow_levels = std::min(c.flow_levels, params.matching_flow_levels);
  }
  return c;
}

int tournament(const std::vector<Individual>& pop, Rng& rng, int exclude) {
  const int n = static_cast<int>(pop.size());
  int a = rng.below(n), b = rng.below(n);
  if (a == exclude) a = (a + 1) % n;
  if (b == exclude) b = (b + 1) % n;
  return pop[a].cut <= pop[b].cut ? a : b;
}

}  // namespace

std::vector<int> evolve(const WorkGraph& g, int k, const std::vector<long long>& ub,
                        const EvolutionParams& params, Rng& rng, const EvolutionTrace& trace) {
  params.validate();
  std::vector<Individual> pop;
  auto best_cut = [&] {
    long long b = pop.front().cut;
    for (const auto& ind : pop) b = std::min(b, ind.cut);
    return b;
  };
  // A fresh partition, with probability light_share under bounds that keep one block light
  // (which one and how light is drawn relative to `like`, e.g. the parent it will combine with).
  auto fresh_partition = [&](const std::vector<int>* like) {
    if (params.light_share > 0.0 && rng.uniform() < params.light_share) {
      const std::vector<int> none(static_cast<std::size_t>(g.n), 0);
      const std::vector<long long> lub =
          random_light_bounds(g, like ? *like : none, ub, params.light_min, params.light_max, rng);
      return multilevel_partition(g, k, lub, varied(params, rng), rng);
    }
    return multilevel_partition(g, k, ub, varied(params, rng), rng);
  };
  auto fresh_individual = [&] {
    Individual ind;
    ind.part = fresh_partition(nullptr);
    ind.cut = edge_cut(g, ind.part);
    for (int c = 0; c < params.vcycles; ++c)
      ind = vcycle(g, k, ub, std::move(ind), varied(params, rng), rng);
    return ind;
  };
  for (int i = 0; i < std::max(1, params.population); ++i) pop.push_back(fresh_individual());
  if (trace)
    trace("population",
          std::to_string(pop.size()) + " multilevel runs + " + std::to_string(params.vcycles) +
              " V-cycles each",
          best_cut());
  int improved = 0, steps = 0, stalled = 0, tail = -1;  // tail: light-only steps left (-1: off)
  for (int gen = 0; gen < params.generations && pop.size() > 1 && tail != 0; ++gen) {
    if (tail < 0 && stalled >= params.stall_limit) {
      if (params.light_tail <= 0) break;
      tail = params.light_tail;
    }
    if (tail > 0) --tail;
    ++steps;
    ++stalled;
    Individual child;
    if (tail >= 0 || (params.light_cycle_share > 0.0 && stalled > params.light_after_stall &&
                      rng.uniform() < params.light_cycle_share)) {
      const Individual& a = pop[tournament(pop, rng, -1)];
      const std::vector<long long> lub =
          random_light_bounds(g, a.part, ub, params.light_min, params.light_max, rng);
      Individual pushed;
      pushed.part = guided_cycle(g, k, lub, a.part, a.part, varied(params, rng), rng);
      pushed.cut = edge_cut(g, pushed.part);
      child = vcycle(g, k, ub, std::move(pushed), varied(params, rng), rng);
    } else if (params.cross_share > 0.0 && stalled > params.cross_after_stall &&
               rng.uniform() < params.cross_share) {
      child = cross_combine(g, k, ub, pop[tournament(pop, rng, -1)], varied(params, rng), rng);
    } else if (rng.uniform() < params.mutation_rate) {
      // Mutation: combine an individual with a fresh multilevel partition.
      const int a = tournament(pop, rng, -1);
      Individual fresh;
      fresh.part = fresh_partition(&pop[a].part);
      fresh.cut = edge_cut(g, fresh.part);
      child = combine(g, k, ub, pop[a], fresh, varied(params, rng), rng);
    } else {
      const int a = tournament(pop, rng, -1);
      const int b = tournament(pop, rng, a);
      child = combine(g, k, ub, pop[a], pop[b], varied(params, rng), rng);
    }
    // Replace the worst individual if the child is better and not already in the population.
    int worst = 0;
    for (int i = 1; i < static_cast<int>(pop.size()); ++i)
      if (pop[i].cut > pop[worst].cut) worst = i;
    bool duplicate = false;
    for (const auto& ind : pop)
      duplicate = duplicate || (ind.cut == child.cut && ind.part == child.part);
    if (!duplicate && child.cut <= pop[worst].cut) {
      if (child.cut < best_cut()) {
        ++improved;
        stalled = 0;
      }
      pop[worst] = std::move(child);
    }
  }
  if (trace && params.generations > 0)
    trace("evolution",
          std::to_string(steps) + " combine/mutation steps, " + std::to_string(improved) +
              " improved the best",
          best_cut());
  int best = 0;
  for (int i = 1; i < static_cast<int>(pop.size()); ++i)
    if (pop[i].cut < pop[best].cut) best = i;
  if (params.polish.rounds > 0) {
    // Its own generator (seeded from a copy of the search's): the spectral layouts below draw
    // exactly what they drew without the polish.
    Rng copy = rng;
    Rng prng(copy.next() ^ 0x5DEECE66DULL);
    const long long before = pop[best].cut;
    pop[best].cut = relaxed_polish(g, k, ub, pop[best].part, params.polish, params.cycle, prng);
    if (trace)
      trace("polish",
            std::to_string(params.polish.rounds) + " relax/repair rounds from " +
                std::to_string(before),
            pop[best].cut);
  }
  if (params.spectral_seeds > 0) {
    // Global layouts after the search (spectral_layouts.hpp): the search itself is exactly the
    // one without them, and they only replace its best when they are better, so the result can
    // only improve. They draw from a copy of the generator for the same reason.
    Rng srng = rng;
    srng.next();
    Individual top = pop[best];
    std::string cuts;
    // Layouts far above the search's best after FM are not worth V-cycles and combines.
    const long long useful =
        static_cast<long long>(static_cast<double>(top.cut) * (1.0 + params.spectral_gap));
    for (auto& p : refined_spectral_layouts(g, k, ub, params.spectral, varied(params, srng),
                                            params.spectral_seeds, srng, useful)) {
      Individual seed{std::move(p), 0};
      seed.cut = edge_cut(g, seed.part);
      cuts += (cuts.empty() ? "" : " ") + std::to_string(seed.cut);
      // Combining keeps what both share: a layout with the right global arrangement can pick
      // up the search's better local boundaries (never worse than the better of the two).
      Individual child = combine(g, k, ub, top, seed, varied(params, srng), srng);
      if (child.cut < top.cut) top = std::move(child);
    }
    if (trace)
      trace("spectral", "global layouts after V-cycles: " + (cuts.empty() ? "none" : cuts),
            top.cut);
    return top.part;
  }
  return pop[best].part;
}

}  // namespace tessera::partition_detail
