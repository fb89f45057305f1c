#include "partition/island_search.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <memory>
#include <tessera/util/input_error.hpp>

#include "partition/evolution_search.hpp"
#include "partition/job_runner.hpp"

namespace tessera::partition_detail {

void IslandOptions::validate() const {
  if (islands < 1 || islands > 8)
    throw InputError("IslandOptions.islands = " + std::to_string(islands) + ": must be in 1..8");
  if (!(second_matching_share == -1.0 ||
        (second_matching_share >= 0.0 && second_matching_share <= 1.0)))
    throw InputError("IslandOptions.second_matching_share = " +
                     std::to_string(second_matching_share) + ": must be -1 or in 0..1");
  if (short_islands < 0 || short_islands > 8)
    throw InputError("IslandOptions.short_islands = " + std::to_string(short_islands) +
                     ": must be in 0..8");
  if (!(short_budget > 0.0 && short_budget <= 1.0))
    throw InputError("IslandOptions.short_budget = " + std::to_string(short_budget) +
                     ": must be in (0, 1]");
  if (exchange_every < 0)
    throw InputError("IslandOptions.exchange_every = " + std::to_string(exchange_every) +
                     ": must be >= 0");
}

namespace {

struct Island {
  Rng rng;
  EvolutionParams params;
  std::unique_ptr<EvolutionSearch> search;
  double cpu_ms = 0.0;
  int taken = 0;                 ///< Individuals from other islands that entered this population.
  long long population_cut = 0;  ///< Best of the initial population.
};

}  // namespace

int short_island_generations(int generations, double short_budget) {
  return std::max(1, static_cast<int>(std::lround(generations * short_budget)));
}

IslandSearchResult island_search(
    const WorkGraph& g, int k, const std::vector<long long>& ub, const EvolutionParams& params,
    Rng& rng, const std::function<void(const std::string&, const std::string&, long long)>& trace,
    const std::vector<std::function<void()>>& side_jobs) {
  params.islands.validate();
  const int full = params.islands.islands;
  const int count = full + params.islands.short_islands;
  // Island 0 runs on the caller's generator; the others get seeds drawn from a copy of it, so
  // the caller's stream (and island 0's search) is the one a single search would draw.
  Rng seeder = rng;
  const std::uint64_t base = seeder.next();
  EvolutionParams second = params;
  if (params.islands.second_matching_share >= 0.0)
    second.matching_share = params.islands.second_matching_share;
  // Reserved: each search keeps references to its island's generator and parameters.
  std::vector<Island> islands;
  islands.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    islands.push_back(Island{i == 0 ? rng : Rng(base ^ (0xA24BAED4963EE407ULL * i)),
                             i == 1 ? second : params, nullptr, 0.0, 0, 0});
    Island& isl = islands.back();
    if (i >= full)
      isl.params.generations =
          short_island_generations(params.generations, params.islands.short_budget);
    isl.search = std::make_unique<EvolutionSearch>(g, k, ub, isl.params, isl.rng);
  }

  // One epoch: every island runs `job` on its own thread (the caller's is one), `extra` in
  // whichever thread is free first; joining them all is the barrier after which individuals
  // are exchanged. A short island on its own thread rather than queued behind a full one: on
  // two cores the system then shares both cores among the three threads, which ends sooner
  // than a short island started only when the first full island ends (rim, loaded host: the
  // larger thread's CPU time was the smaller full island plus the short one, ~1 s above half
  // of the total).
  std::vector<double> thread_cpu;  // per worker thread, summed over the epochs
  auto epoch = [&](auto job, const std::vector<std::function<void()>>& extra) {
    std::vector<std::function<void()>> jobs;
    for (auto& isl : islands)
      jobs.emplace_back([&isl, &job] {
        const double c0 = thread_cpu_ms();
        job(isl);
        isl.cpu_ms += thread_cpu_ms() - c0;
      });
    jobs.insert(jobs.end(), extra.begin(), extra.end());
    const std::vector<double> cpu = run_jobs(jobs, count);
    thread_cpu.resize(std::max(thread_cpu.size(), cpu.size()), 0.0);
    for (std::size_t t = 0; t < cpu.size(); ++t) thread_cpu[t] += cpu[t];
  };

  const int chunk = params.islands.exchange_every > 0 ? params.islands.exchange_every : INT_MAX;
  const bool exchanges = params.islands.exchange_every > 0 && count > 1;
  // Without exchanges an island builds its population and searches in one job, so a thread
  // never waits for the others between the two.
  epoch(
      [&](Island& isl) {
        isl.search->build_population();
        isl.population_cut = isl.search->best().cut;
        if (!exchanges) isl.search->run(INT_MAX);
      },
      side_jobs);
  if (trace) {
    long long cut = LLONG_MAX;
    for (auto& isl : islands) cut = std::min(cut, isl.population_cut);
    trace("population",
          (count > 1 ? std::to_string(count) + " islands x " : std::string()) +
              std::to_string(params.population) + " multilevel runs + " +
              std::to_string(params.vcycles) + " V-cycles each" +
              (exchanges || count == 1
                   ? ""
                   : " (each island searched on in the same job: this time is the search's)"),
          cut);
  }

  auto running = [&] {
    for (auto& isl : islands)
      if (!isl.search->ended()) return true;
    return false;
  };
  while (exchanges && running()) {
    epoch([chunk](Island& isl) { isl.search->run(chunk); }, {});
    // Snapshot every island's best first, so the order of the offers changes nothing.
    std::vector<Individual> bests;
    for (auto& isl : islands) bests.push_back(isl.search->best());
    for (int i = 0; i < count; ++i) {
      if (islands[i].search->ended()) continue;
      int from = -1;
      for (int j = 0; j < count; ++j)
        if (j != i && (from < 0 || bests[j].cut < bests[from].cut)) from = j;
      if (islands[i].search->offer(bests[from])) ++islands[i].taken;
    }
  }

  int winner = 0;
  for (int i = 1; i < count; ++i)
    if (islands[i].search->best().cut < islands[winner].search->best().cut) winner = i;
  IslandSearchResult result{islands[winner].search->best().part,
                            islands[winner].search->best().cut};
  if (trace && params.generations > 0) {
    std::string detail;
    for (int i = 0; i < count; ++i) {
      const auto& s = *islands[i].search;
      std::string steps = std::to_string(s.steps()) + " combine/mutation steps, " +
                          std::to_string(s.improved()) + " improved the best";
      if (s.improved() > 0)
        steps += " (last at step " + std::to_string(s.last_improved_step()) + ")";
      if (count == 1) {
        detail = steps;  // one island: the plain search's trace, no island prefix
        break;
      }
      detail += (i > 0 ? "; " : "") + ("island " + std::to_string(i) + ": ") +
                (i >= full ? "short, " : "") + steps + ", " + std::to_string(islands[i].taken) +
                " migrants taken, best " + std::to_string(s.best().cut) + ", thread cpu " +
                std::to_string(static_cast<long long>(islands[i].cpu_ms)) + " ms";
    }
    if (count > 1) {
      detail += "; winner island " + std::to_string(winner) + "; worker threads cpu";
      for (double c : thread_cpu) detail += " " + std::to_string(static_cast<long long>(c));
      detail += " ms";
    }
    trace("evolution", detail, result.cut);
  }
  // The caller's generator continues from island 0's state (the single search's stream).
  rng = islands[0].rng;
  return result;
}

}  // namespace tessera::partition_detail
