#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <tessera/partition/partitioner.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/evolutionary.hpp"
#include "partition/multilevel.hpp"
#include "partition/quotient_colouring.hpp"

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
  throw InputError("unknown preset '" + name +
                   "' (valid: sequential, fast, eco, strong, highest; solve and launch: auto)");
}

PartitionPreset auto_preset(std::size_t num_vertices) {
  return num_vertices < kAutoPresetFastBelow ? PartitionPreset::kFast : PartitionPreset::kEco;
}

PartitionPreset parse_preset_for(const std::string& name, std::size_t num_vertices) {
  if (name == "auto") return auto_preset(num_vertices);
  return parse_preset(name);
}

const char* objective_name(PartitionObjective objective) {
  return objective == PartitionObjective::kRounds ? "rounds" : "cut";
}

PartitionObjective parse_objective(const std::string& name) {
  if (name == "cut") return PartitionObjective::kCut;
  if (name == "rounds") return PartitionObjective::kRounds;
  throw InputError("unknown partition objective '" + name + "' (valid: cut, rounds)");
}

void PartitionOptions::validate() const {
  if (parts < 1 || parts > 64)
    throw InputError("PartitionOptions.parts = " + std::to_string(parts) + ": must be in 1..64");
  if (!std::isfinite(eps) || eps < 0.0 || eps > 1.0)
    throw InputError("PartitionOptions.eps = " + std::to_string(eps) + ": must be in 0..1");
  if (islands < 0 || islands > 8)
    throw InputError("PartitionOptions.islands = " + std::to_string(islands) +
                     ": must be in 0..8 (0 = the preset's own)");
  if (!std::isfinite(colour_cut_slack) || colour_cut_slack < 0.0 || colour_cut_slack > 10.0)
    throw InputError("PartitionOptions.colour_cut_slack = " + std::to_string(colour_cut_slack) +
                     ": must be in 0..10");
  if (!std::isfinite(time_limit_s) || time_limit_s < 0.0)
    throw InputError("PartitionOptions.time_limit_s = " + std::to_string(time_limit_s) +
                     ": must be >= 0 seconds (0 = no cap)");
  if (stall_steps < 0)
    throw InputError("PartitionOptions.stall_steps = " + std::to_string(stall_steps) +
                     ": must be >= 0 (0 = the preset's own)");
}

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double cpu_ms_since(std::clock_t c0) {
  return 1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
}

// Per-preset effort (see docs/partitioning.md). Shared by all presets: coarse vertices stay
// below lmax/30 so the coarsest graph (a few dozen vertices per block) can still be balanced.
struct PresetPlan {
  CycleParams cycle;
  int runs = 1;     ///< fast/eco: independent multilevel runs, best kept.
  int vcycles = 0;  ///< fast/eco: V-cycles on the best run.
  bool evolve = false;
  EvolutionParams evolution;  ///< strong/highest.
};

// Size ((n + edges) x max(1, N/5), the unit of the search's operation budget) up to which
// `highest` re-splits its best partition (block_resplit.hpp): torus3D (14048) and the smaller
// benchmark graphs at N <= 5; cubicle (18236) and the larger ones spend ~3-4.4 s already.
constexpr double kResplitSize = 16000.0;
// Larger problems: sub-searches (0 = none), a sub-search's share of the step budget, and how
// separable the kept block must be (BlockResplitOptions::max_cut_ratio).
constexpr int kResplitLargeSearches = 4;
constexpr double kResplitLargeBudget = 0.5;
constexpr double kResplitCutRatio = 0.6;

PresetPlan preset_plan(PartitionPreset preset, const WorkGraph& g, int k, long long lmax) {
  PresetPlan plan;
  CycleParams& cp = plan.cycle;
  cp.coarsening.stop_vertices = std::max(20 * k, 80);
  cp.coarsening.max_vertex_weight = static_cast<int>(std::max<long long>(2, lmax / 30));
  cp.initial.repeats = 4;
  cp.initial.bisection_tries = 4;
  switch (preset) {
    case PartitionPreset::kFast:
      cp.fm.max_passes = 2;
      cp.fm.stop_after = 40;
      // Initial partitioning dominated fast at many blocks (73 % of grid3D N = 25: coarse
      // vertices stay below lmax/30, so its coarsest graph has ~1100 vertices). From 12 blocks
      // on, the runs shrink with the coarsest graph (3 around 600 vertices, i.e. N = 16; 2 from
      // ~900, N = 25) and a third FM pass per level wins back what the fewer runs lose (cut
      // geomean ratio 1.007, grid3D N = 25 CPU 45 -> 32 ms; docs/partitioning.md). Below 12
      // blocks fast is cheap and unchanged.
      if (k >= 12) {
        cp.fm.max_passes = 3;
        cp.initial.repeat_budget = 1600;
        cp.initial.min_repeats = 2;
      }
      break;
    case PartitionPreset::kEco:
      cp.coarsening.label_propagation_rounds = 3;
      cp.initial.repeats = 10;
      cp.fm.max_passes = 6;
      cp.fm.stop_after = 400;
      cp.use_flow = true;
      cp.flow_levels = 1;
      cp.flow.rounds = 1;
      cp.flow.alpha = 4;
      plan.runs = 2;
      plan.vcycles = 1;
      break;
    case PartitionPreset::kStrong:
    case PartitionPreset::kHighest:
      cp.coarsening.label_propagation_rounds = 3;
      cp.initial.repeats = 10;
      cp.fm.max_passes = 6;
      cp.fm.stop_after = 400;
      cp.use_flow = true;
      cp.flow_levels = 3;
      plan.evolve = true;
      {
        // Effort in multilevel operations, scaled so that every graph gets about the same
        // time: one operation costs roughly proportional to n + edges.
        const double size = static_cast<double>(g.n) + static_cast<double>(g.adj.size()) / 2.0;
        // More blocks make every operation dearer (more block pairs for the flows).
        // (Exponent 1: with 0.8, highest on grid3D took 4.8 s CPU at N = 16.)
        const double per_op = size * std::max(1.0, k / 5.0);
        const bool strong = preset == PartitionPreset::kStrong;
        const int ops = static_cast<int>(
            std::clamp((strong ? 1.6e6 : 2.8e6) / per_op, 12.0, strong ? 400.0 : 800.0));
        plan.evolution.population = strong ? 4 : 8;
        // Half of the steps are mutations (a fresh multilevel partition combined with a
        // tournament winner) in both; with 0.3 strong's 4 individuals converged early on rim
        // (271/271/243 on seeds 1-3, 275/275 on 4-5; with 0.5: 247/267/243, 259/252).
        plan.evolution.mutation_rate = 0.5;
        plan.evolution.vcycles = 1;
        plan.evolution.generations = std::max(4, ops - 2 * plan.evolution.population);
        // Small graphs converge long before the budget is spent.
        plan.evolution.stall_limit = std::max(40, plan.evolution.generations / 3);
        // highest: half of its operations coarsen by heavy-edge matching instead of label
        // propagation (flows then only on the input graph, see EvolutionParams).
        plan.evolution.matching_share = strong ? 0.0 : 0.5;
        plan.evolution.matching_flow_levels = 0;
        // highest: once 8 steps in a row found no new best, 30 % of its steps cross-combine
        // with a cheap partition into another number of blocks (KaFFPaE). From the start it
        // helped rim/grid3D but cost parking-garage its 28 (32) and intel 1; as a diversification
        // after a stall it keeps both (docs/partitioning.md).
        plan.evolution.cross_share = strong ? 0.0 : 0.3;
        plan.evolution.cross_after_stall = 8;
        // When the search stalls before its budget is spent, up to 40 more steps push
        // tournament winners towards one light block (a V-cycle under bounds that keep that
        // block at 0.88-0.98 of the average, then one under the real bounds). The best known
        // cuts mostly have one light block and the others at the bound (rim 2100 2096 1867 2032
        // 2100). As a tail the search before it is unchanged, so no cut gets worse; mixed into
        // the whole search it lost city10000/grid3D (docs/partitioning.md, item 7).
        plan.evolution.light_tail = 40;
        // highest: after the search, the 2 best global layouts read off the Laplacian
        // embedding (bands, a + b layouts, arcs around rings; spectral_layouts.hpp) are
        // combined with its best and replace it when better. The search before is unchanged,
        // so no cut gets worse; sphere2500 (a twisted cylinder) gets the seam-aligned 3 + 2
        // layout (179) that the search never reaches (180 on every seed).
        plan.evolution.spectral_seeds = strong ? 0 : 2;
        // highest: the search's best then gets 4 relax / repair rounds (relaxed_polish.hpp):
        // FM and flows under bounds raised by 0.2-3 %, rebalance, FM and flows under the real
        // bound. With several blocks at the bound a better cut can need a chain of moves that
        // no bounded move starts (rim seed 4: 247 -> 243, 10 vertices). After the search, so
        // the search is unchanged and no cut gets worse; it helps most at large N, where the
        // search has few steps (rim N = 25: 1167 -> 1155).
        plan.evolution.polish.rounds = strong ? 0 : 4;
        // highest: two islands (island_search.hpp), each with all of the budget above on its
        // own thread. One search settles into one global arrangement (rim: 258 or 243 by
        // seed); two independent ones reach the better one more often for the same wall time
        // on two cores. A fixed count, not the machine's core count, so that a seed gives the
        // same partition everywhere. No exchanges: with exchanges the islands fell into one
        // arrangement early (docs/partitioning.md, item 10). Four islands (`--islands 4`) cost
        // twice the CPU for no other small graph's gain, so two stay the default.
        plan.evolution.islands.islands = strong ? 1 : 2;
        plan.evolution.islands.exchange_every = 0;
        // highest: and a third, short island (a fifth of the step budget, its own thread):
        // the first steps of what a full third island would search, a cheap further draw of
        // the arrangement lottery. The full third island reached its better arrangement early
        // on rim seed 1 (246 instead of 258, at step 11 of 70), torus3D seed 4 (243 instead of
        // 246, step 8) and city10000 seed 3 (131 instead of 134, step 8); a fifth (rim 14
        // steps) keeps all three for ~1.1 s CPU on rim, about half of it wall time on two
        // cores (docs/partitioning.md, item 10).
        // Only where its steps are at least as many as its population: a short island costs
        // its population (2 x population operations) plus its steps, so with a small step
        // budget (many blocks: rim/grid3D N = 25 get 4 steps) it would cost ~75 % of a full
        // island for one step of search (grid3D N = 25: +2.4 s thread CPU).
        plan.evolution.islands.short_budget = 0.2;
        const int short_steps = short_island_generations(plan.evolution.generations,
                                                         plan.evolution.islands.short_budget);
        plan.evolution.islands.short_islands =
            !strong && short_steps >= plan.evolution.population ? 1 : 0;
        // highest, small problems only: last, two sub-searches (one thread each) keep the best
        // partition's 2 most separable blocks and search the rest again from scratch
        // (block_resplit.hpp), each with a population of 4 and the full step budget; the result
        // replaces the best only when strictly better, so no cut gets worse. The search settles
        // into one arrangement of the blocks; this is a new draw for the blocks that are not yet
        // right (torus3D seeds 1, 7, 8: 242/241/245 -> 240/240/243, keeping its two strips). Only
        // where (n + edges) x max(1, N/5) <= 16000 (torus3D and smaller at N = 4, 5): there the
        // whole run costs <= ~2.2 s idle and the sub-searches add ~0.3-1 s; on rim / city10000 /
        // grid3D they would pass 5 s (docs/partitioning.md, item 11).
        if (!strong && per_op <= kResplitSize) plan.evolution.resplit.searches = 2;
        plan.evolution.resplit.kept = 2;
        plan.evolution.resplit.population = 4;
        plan.evolution.resplit.budget = 1.0;
        // highest, larger problems: cheaper sub-searches (half the budget) that
        // keep only the most separable block, and only when it is clearly separable (its cut
        // edges at most kResplitCutRatio x the mean block cut). rim's light block (49 cut
        // edges, mean 98) is shared by its 246 and 243 partitions, which arrange the other four
        // blocks differently; a fresh search of those four found the 243 arrangement in 1/5-1/3
        // of the tries. Meshes (grid3D 0.92) and city10000 (0.81) have no such block and keep
        // their time (docs/partitioning.md, item 11). Four sub-searches, paid for by the cheap
        // max flows (flow_refinement.cpp): rim seeds 1, 10, 15 reach 243 with four, not two.
        if (!strong && per_op > kResplitSize) {
          plan.evolution.resplit.searches = kResplitLargeSearches;
          plan.evolution.resplit.kept = 1;
          plan.evolution.resplit.budget = kResplitLargeBudget;
          plan.evolution.resplit.max_cut_ratio = kResplitCutRatio;
        }
        // Coarse levels balance to 1.03 x the bound, the input graph to the bound itself. The
        // best cuts often have one light block and the others at the bound; with the exact
        // bound on every level the coarse searches rarely reach such shapes (highest intel 34
        // instead of 35, grid3D 925 instead of 943 at seed 1).
        cp.coarse_relax = 0.03;
      }
      break;
    default:
      break;
  }
#ifdef TESSERA_PARTITION_TUNING
  // Developer hooks for parameter sweeps (never compiled into the normal build).
  auto env = [](const char* name) { return std::getenv(name); };
  if (env("T_FLOW")) cp.use_flow = std::atoi(env("T_FLOW")) > 0;
  if (env("T_ALPHA")) cp.flow.alpha = std::atof(env("T_ALPHA"));
  if (env("T_FLEV")) cp.flow_levels = std::atoi(env("T_FLEV"));
  if (env("T_CRELAX")) cp.coarse_relax = std::atof(env("T_CRELAX"));
  if (env("T_FROUNDS")) cp.flow.rounds = std::atoi(env("T_FROUNDS"));
  if (env("T_LOC")) cp.fm.local_rounds = std::atoi(env("T_LOC"));
  if (env("T_LOCSTOP")) cp.fm.local_stop_after = std::atoi(env("T_LOCSTOP"));
  if (env("T_STOP")) cp.fm.stop_after = std::atoi(env("T_STOP"));
  if (env("T_PASS")) cp.fm.max_passes = std::atoi(env("T_PASS"));
  if (env("T_CSTOP")) cp.coarsening.stop_vertices = std::atoi(env("T_CSTOP")) * k;
  if (env("T_MAXW"))
    cp.coarsening.max_vertex_weight =
        static_cast<int>(std::max<long long>(1, lmax / std::atoi(env("T_MAXW"))));
  if (env("T_LP")) cp.coarsening.label_propagation_rounds = std::atoi(env("T_LP"));
  if (env("T_REP")) cp.initial.repeats = std::atoi(env("T_REP"));
  if (env("T_BUDGET")) cp.initial.repeat_budget = std::atoi(env("T_BUDGET"));
  if (env("T_MINREP")) cp.initial.min_repeats = std::atoi(env("T_MINREP"));
  if (env("T_BTRY")) cp.initial.bisection_tries = std::atoi(env("T_BTRY"));
  if (env("T_RUNS")) plan.runs = std::atoi(env("T_RUNS"));
  if (env("T_VCYC")) plan.vcycles = std::atoi(env("T_VCYC"));
  if (env("T_POP")) plan.evolution.population = std::atoi(env("T_POP"));
  if (env("T_GEN")) plan.evolution.generations = std::atoi(env("T_GEN"));
  if (env("T_VC")) plan.evolution.vcycles = std::atoi(env("T_VC"));
  if (env("T_MUT")) plan.evolution.mutation_rate = std::atof(env("T_MUT"));
  if (env("T_MATCH")) plan.evolution.matching_share = std::atof(env("T_MATCH"));
  if (env("T_STALL")) plan.evolution.stall_limit = std::atoi(env("T_STALL"));
  if (env("T_XSTALL")) plan.evolution.cross_after_stall = std::atoi(env("T_XSTALL"));
  if (env("T_CROSS")) plan.evolution.cross_share = std::atof(env("T_CROSS"));
  if (env("T_LIGHT")) plan.evolution.light_share = std::atof(env("T_LIGHT"));
  if (env("T_LCYC")) plan.evolution.light_cycle_share = std::atof(env("T_LCYC"));
  if (env("T_LSTALL")) plan.evolution.light_after_stall = std::atoi(env("T_LSTALL"));
  if (env("T_LTAIL")) plan.evolution.light_tail = std::atoi(env("T_LTAIL"));
  if (env("T_LMIN")) plan.evolution.light_min = std::atof(env("T_LMIN"));
  if (env("T_LMAX")) plan.evolution.light_max = std::atof(env("T_LMAX"));
  if (env("T_SPEC")) plan.evolution.spectral_seeds = std::atoi(env("T_SPEC"));
  if (env("T_SPECEV")) plan.evolution.spectral.eigenvectors = std::atoi(env("T_SPECEV"));
  if (env("T_SPECROT")) plan.evolution.spectral.rotations = std::atoi(env("T_SPECROT"));
  if (env("T_SPECGAP")) plan.evolution.spectral_gap = std::atof(env("T_SPECGAP"));
  if (env("T_SPECPOL")) plan.evolution.spectral.polish = std::atoi(env("T_SPECPOL"));
  if (env("T_SPECTOL")) plan.evolution.spectral.lanczos_tolerance = std::atof(env("T_SPECTOL"));
  if (env("T_POL")) plan.evolution.polish.rounds = std::atoi(env("T_POL"));
  if (env("T_POLMIN")) plan.evolution.polish.min_relax = std::atof(env("T_POLMIN"));
  if (env("T_POLMAX")) plan.evolution.polish.max_relax = std::atof(env("T_POLMAX"));
  if (env("T_MFLEV")) plan.evolution.matching_flow_levels = std::atoi(env("T_MFLEV"));
  if (env("T_ISL")) plan.evolution.islands.islands = std::atoi(env("T_ISL"));
  if (env("T_I1MATCH")) plan.evolution.islands.second_matching_share = std::atof(env("T_I1MATCH"));
  if (env("T_SHORT")) plan.evolution.islands.short_islands = std::atoi(env("T_SHORT"));
  if (env("T_SHORTF")) plan.evolution.islands.short_budget = std::atof(env("T_SHORTF"));
  if (env("T_XCH")) plan.evolution.islands.exchange_every = std::atoi(env("T_XCH"));
  if (env("T_RS")) plan.evolution.resplit.searches = std::atoi(env("T_RS"));
  if (env("T_RSKEEP")) plan.evolution.resplit.kept = std::atoi(env("T_RSKEEP"));
  if (env("T_RSPOP")) plan.evolution.resplit.population = std::atoi(env("T_RSPOP"));
  if (env("T_RSB")) plan.evolution.resplit.budget = std::atof(env("T_RSB"));
  if (env("T_RSRATIO")) plan.evolution.resplit.max_cut_ratio = std::atof(env("T_RSRATIO"));
  if (env("T_OPS"))
    plan.evolution.generations =
        static_cast<int>(plan.evolution.generations * std::atof(env("T_OPS")));
#endif
  cp.initial.fm = cp.fm;
  plan.evolution.cycle = cp;
  return plan;
}

}  // namespace

BlockAdjacency block_adjacency(const GraphStructure& graph, const std::vector<int>& assignment,
                               int parts) {
  compute_partition_metrics(graph, assignment, parts);  // validates the assignment
  const QuotientColouring q = colour_quotient(to_work_graph(graph), assignment, parts);
  return {q.adjacent_pairs, q.colours};
}

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
  const std::clock_t c0 = std::clock();
  auto phase = [&](const std::string& name, const std::string& detail, long long cut,
                   Clock::time_point since) {
    result.trace.push_back({name, detail, cut, ms_since(since)});
  };

  if (options.preset == PartitionPreset::kSequential || k == 1) {
    result.assignment = sequential_partition(n, k);
    result.time_ms = ms_since(t0);
    result.cpu_ms = cpu_ms_since(c0);
    result.metrics = compute_partition_metrics(graph, result.assignment, k);
    phase("sequential", std::to_string(k) + " contiguous id ranges",
          static_cast<long long>(result.metrics.cut_edges), t0);
    const QuotientColouring q = colour_quotient(to_work_graph(graph), result.assignment, k);
    result.adjacent_block_pairs = q.adjacent_pairs;
    result.colours = q.colours;
    return result;
  }

  const WorkGraph g = to_work_graph(graph);
  const long long lmax = static_cast<long long>(result.max_block_size);
  const std::vector<long long> ub(static_cast<std::size_t>(k), lmax);
  PresetPlan plan = preset_plan(options.preset, g, k, lmax);
  if (options.islands > 0) {
    plan.evolution.islands.islands = options.islands;
    // One island is the single search on the calling thread, without the short one or the
    // re-split's sub-searches: a caller asking for one wants the cheapest search (e.g. one that
    // shares the cores).
    if (options.islands == 1) {
      plan.evolution.islands.short_islands = 0;
      plan.evolution.resplit.searches = 0;
    }
  }
  if (options.stall_steps > 0) plan.evolution.stall_limit = options.stall_steps;
  if (options.time_limit_s > 0.0)
    plan.evolution.deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(options.time_limit_s));
  const CycleParams& cp = plan.cycle;
  Rng rng(options.seed);
  std::vector<int> part;

  auto describe = [](const CycleStats& s) {
    return std::to_string(s.levels) + " levels, coarsest " + std::to_string(s.coarsest_vertices) +
           " vertices (cut there " + std::to_string(s.coarsest_cut) + ")";
  };
  if (!plan.evolve) {
    long long best = -1;
    for (int r = 0; r < plan.runs; ++r) {
      if (r > 0 && plan.evolution.past_deadline()) break;
      const auto tr = Clock::now();
      CycleStats s;
      std::vector<int> p = multilevel_partition(g, k, ub, cp, rng, &s);
      if (best < 0 || s.cut < best) {
        best = s.cut;
        part.swap(p);
      }
      phase("multilevel", describe(s), best, tr);
    }
    for (int c = 0; c < plan.vcycles; ++c) {
      if (plan.evolution.past_deadline()) break;
      const auto tc = Clock::now();
      CycleStats s;
      std::vector<int> p = guided_cycle(g, k, ub, part, part, cp, rng, &s);
      if (s.cut <= best) {
        best = s.cut;
        part.swap(p);
      }
      phase("v-cycle", describe(s), best, tc);
    }
  } else {
    auto tp = Clock::now();
    part = evolve(g, k, ub, plan.evolution, rng,
                  [&](const std::string& name, const std::string& detail, long long cut) {
                    phase(name, detail, cut, tp);
                    tp = Clock::now();
                  });
  }
  rebalance(g, k, part, ub);  // no-op for balanced results; a safety net for the promise above
  if (options.objective == PartitionObjective::kRounds && k > 2) {
    const auto tc = Clock::now();
    ColourPassOptions co;
    co.max_cut_increase = options.colour_cut_slack;
    // The constrained FM is the pass's only refinement (flows ignore the constraint), so it
    // gets at least the strong presets' effort whatever the preset (milliseconds).
    co.fm = cp.fm;
    co.fm.max_passes = std::max(co.fm.max_passes, 6);
    co.fm.stop_after = std::max(co.fm.stop_after, 400);
    co.fm.local_rounds = std::max(co.fm.local_rounds, 2);
    const ColourPassResult cr = colour_pass(g, k, ub, part, co, rng);
    phase("colours",
          std::to_string(cr.colours_before) + " -> " + std::to_string(cr.colours_after) +
              " colours (cut " + std::to_string(cr.cut_before) + " -> " +
              std::to_string(cr.cut_after) + ")",
          cr.cut_after, tc);
  }
  const QuotientColouring q = colour_quotient(g, part, k);
  result.adjacent_block_pairs = q.adjacent_pairs;
  result.colours = q.colours;
  result.assignment = std::move(part);
  result.time_ms = ms_since(t0);
  result.cpu_ms = cpu_ms_since(c0);
  result.metrics = compute_partition_metrics(graph, result.assignment, k);
  return result;
}

}  // namespace tessera
