#include "partition/evolutionary.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <tessera/util/input_error.hpp>

#include "partition/evolution_search.hpp"
#include "partition/island_search.hpp"

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
  islands.validate();
  resplit.validate();
  spectral.validate();
}

std::vector<int> evolve(const WorkGraph& g, int k, const std::vector<long long>& ub,
                        const EvolutionParams& params, Rng& rng, const EvolutionTrace& trace) {
  params.validate();
  // Spectral layouts (spectral_layouts.hpp) come after the search and only replace its best
  // when better, so the search is exactly the one without them and no cut can get worse. Their
  // first half (embedding, layouts, FM) needs nothing from the search, so it runs as a side job
  // of the islands in whichever thread is free first; its generator is seeded from the state
  // before the search, so thread timing changes nothing.
  const bool spectral = params.spectral_seeds > 0;
  Rng srng(Rng(rng).next() ^ 0x9E3779B97F4A7C15ULL);
  const CycleParams scycle = spectral ? varied(params, srng) : params.cycle;
  std::vector<RefinedLayout> layouts;
  std::vector<std::function<void()>> side_jobs;
  if (spectral)
    side_jobs.emplace_back(
        [&] { layouts = fm_refined_layouts(g, k, ub, params.spectral, scycle, srng); });
  IslandSearchResult found = island_search(g, k, ub, params, rng, trace, side_jobs);
  Individual top{std::move(found.part), found.cut};
  if (params.polish.rounds > 0 && !params.past_deadline()) {
    // Its own generator (seeded from a copy of the search's).
    Rng copy = rng;
    Rng prng(copy.next() ^ 0x5DEECE66DULL);
    const long long before = top.cut;
    top.cut = relaxed_polish(g, k, ub, top.part, params.polish, params.cycle, prng);
    if (trace)
      trace("polish",
            std::to_string(params.polish.rounds) + " relax/repair rounds from " +
                std::to_string(before),
            top.cut);
  }
  if (spectral && !params.past_deadline()) {
    std::string cuts;
    // Layouts far above the search's best after FM are not worth V-cycles and combines.
    const long long useful =
        static_cast<long long>(static_cast<double>(top.cut) * (1.0 + params.spectral_gap));
    for (auto& p : finished_layouts(g, k, ub, params.spectral, scycle, std::move(layouts),
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
  }
  if (params.resplit.searches > 0 && k <= params.resplit.max_parts && !params.past_deadline()) {
    const long long before = top.cut;
    const BlockResplitResult r = block_resplit(g, k, ub, top.part, params, rng);
    top.cut = r.cut;
    if (trace) {
      std::string detail =
          "from " + std::to_string(before) + "; " + r.detail + "; worker threads cpu";
      for (double c : r.thread_cpu_ms) detail += " " + std::to_string(static_cast<long long>(c));
      trace("resplit", detail + " ms", top.cut);
    }
  }
  return top.part;
}

}  // namespace tessera::partition_detail
