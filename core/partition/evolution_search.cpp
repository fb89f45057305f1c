#include "partition/evolution_search.hpp"

#include <algorithm>
#include <cmath>

#include "partition/light_block.hpp"

namespace tessera::partition_detail {

namespace {

// One label per (block in a, block in b); b has kb blocks.
std::vector<int> pair_label(const std::vector<int>& a, const std::vector<int>& b, int kb) {
  std::vector<int> label(a.size());
  for (std::size_t v = 0; v < a.size(); ++v) label[v] = a[v] * kb + b[v];
  return label;
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
  CycleStats s;  // its cut is the exact final one: no rescan of the graph
  std::vector<int> p = guided_cycle(g, k, ub, pair_label(a.part, other, kx), a.part, cp, rng, &s);
  const long long cut = s.cut;
  if (cut <= a.cut) return {std::move(p), cut};
  return a;
}

int tournament(const std::vector<Individual>& pop, Rng& rng, int exclude) {
  const int n = static_cast<int>(pop.size());
  int a = rng.below(n), b = rng.below(n);
  if (a == exclude) a = (a + 1) % n;
  if (b == exclude) b = (b + 1) % n;
  return pop[a].cut <= pop[b].cut ? a : b;
}

}  // namespace

Individual vcycle(const WorkGraph& g, int k, const std::vector<long long>& ub, Individual ind,
                  const CycleParams& cp, Rng& rng) {
  CycleStats s;
  std::vector<int> p = guided_cycle(g, k, ub, ind.part, ind.part, cp, rng, &s);
  const long long cut = s.cut;
  if (cut <= ind.cut) return {std::move(p), cut};
  return ind;
}

Individual combine(const WorkGraph& g, int k, const std::vector<long long>& ub, const Individual& a,
                   const Individual& b, const CycleParams& cp, Rng& rng) {
  const Individual& better = a.cut <= b.cut ? a : b;
  CycleStats s;
  std::vector<int> p =
      guided_cycle(g, k, ub, pair_label(a.part, b.part, k), better.part, cp, rng, &s);
  const long long cut = s.cut;
  if (cut <= better.cut) return {std::move(p), cut};
  return better;
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

EvolutionSearch::EvolutionSearch(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                 const EvolutionParams& params, Rng& rng)
    : g_(g), k_(k), ub_(ub), params_(params), rng_(rng) {}

// A fresh partition, with probability light_share under bounds that keep one block light
// (which one and how light is drawn relative to `like`, e.g. the parent it will combine with).
std::vector<int> EvolutionSearch::fresh_partition(const std::vector<int>* like) {
  if (params_.light_share > 0.0 && rng_.uniform() < params_.light_share) {
    const std::vector<int> none(static_cast<std::size_t>(g_.n), 0);
    const std::vector<long long> lub = random_light_bounds(
        g_, like ? *like : none, ub_, params_.light_min, params_.light_max, rng_);
    return multilevel_partition(g_, k_, lub, varied(params_, rng_), rng_);
  }
  return multilevel_partition(g_, k_, ub_, varied(params_, rng_), rng_);
}

Individual EvolutionSearch::fresh_individual() {
  Individual ind;
  ind.part = fresh_partition(nullptr);
  ind.cut = edge_cut(g_, ind.part);
  for (int c = 0; c < params_.vcycles; ++c)
    ind = vcycle(g_, k_, ub_, std::move(ind), varied(params_, rng_), rng_);
  return ind;
}

void EvolutionSearch::build_population() {
  for (int i = 0; i < std::max(1, params_.population); ++i) {
    if (i > 0 && params_.past_deadline()) break;
    pop_.push_back(fresh_individual());
  }
}

const Individual& EvolutionSearch::best() const {
  int best = 0;
  for (int i = 1; i < static_cast<int>(pop_.size()); ++i)
    if (pop_[i].cut < pop_[best].cut) best = i;
  return pop_[best];
}

bool EvolutionSearch::run(int max_steps) {
  for (int i = 0; i < max_steps && !ended_; ++i)
    if (!step()) ended_ = true;
  return !ended_;
}

bool EvolutionSearch::step() {
  if (gen_ >= params_.generations || pop_.size() <= 1 || tail_ == 0) return false;
  if (params_.past_deadline()) return false;
  if (tail_ < 0 && stalled_ >= params_.stall_limit) {
    if (params_.light_tail <= 0) return false;
    tail_ = params_.light_tail;
  }
  if (tail_ > 0) --tail_;
  ++gen_;
  ++steps_;
  ++stalled_;
  Individual child;
  if (tail_ >= 0 || (params_.light_cycle_share > 0.0 && stalled_ > params_.light_after_stall &&
                     rng_.uniform() < params_.light_cycle_share)) {
    const Individual& a = pop_[tournament(pop_, rng_, -1)];
    const std::vector<long long> lub =
        random_light_bounds(g_, a.part, ub_, params_.light_min, params_.light_max, rng_);
    Individual pushed;
    pushed.part = guided_cycle(g_, k_, lub, a.part, a.part, varied(params_, rng_), rng_);
    pushed.cut = edge_cut(g_, pushed.part);
    child = vcycle(g_, k_, ub_, std::move(pushed), varied(params_, rng_), rng_);
  } else if (params_.cross_share > 0.0 && stalled_ > params_.cross_after_stall &&
             rng_.uniform() < params_.cross_share) {
    child =
        cross_combine(g_, k_, ub_, pop_[tournament(pop_, rng_, -1)], varied(params_, rng_), rng_);
  } else if (rng_.uniform() < params_.mutation_rate) {
    // Mutation: combine an individual with a fresh multilevel partition.
    const int a = tournament(pop_, rng_, -1);
    Individual fresh;
    fresh.part = fresh_partition(&pop_[a].part);
    fresh.cut = edge_cut(g_, fresh.part);
    child = combine(g_, k_, ub_, pop_[a], fresh, varied(params_, rng_), rng_);
  } else {
    const int a = tournament(pop_, rng_, -1);
    const int b = tournament(pop_, rng_, a);
    child = combine(g_, k_, ub_, pop_[a], pop_[b], varied(params_, rng_), rng_);
  }
  bool new_best = false;
  insert(std::move(child), &new_best);
  if (new_best) {
    ++improved_;
    last_improved_step_ = steps_;
  }
  return true;
}

// Replaces the worst individual if `child` is no worse and not already in the population; a new
// best resets the stall count. Returns whether it was taken; *new_best says whether it was a
// new best.
bool EvolutionSearch::insert(Individual child, bool* new_best) {
  *new_best = false;
  int worst = 0;
  for (int i = 1; i < static_cast<int>(pop_.size()); ++i)
    if (pop_[i].cut > pop_[worst].cut) worst = i;
  bool duplicate = false;
  for (const auto& ind : pop_)
    duplicate = duplicate || (ind.cut == child.cut && ind.part == child.part);
  if (duplicate || child.cut > pop_[worst].cut) return false;
  *new_best = child.cut < best().cut;
  if (*new_best) stalled_ = 0;
  pop_[worst] = std::move(child);
  return true;
}

bool EvolutionSearch::offer(const Individual& ind) {
  // Only a strictly better individual may enter: a worse one would still displace the worst
  // and change the course of a search that is doing better on its own (rim seed 1 with every
  // migrant taken: 259 instead of the single search's 258).
  if (ind.cut >= best().cut) return false;
  bool new_best = false;
  return insert(ind, &new_best);
}

}  // namespace tessera::partition_detail
