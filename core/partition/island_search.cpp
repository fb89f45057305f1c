#include "partition/island_search.hpp"

#include <time.h>

#include <algorithm>
#include <climits>
#include <exception>
#include <memory>
#include <thread>

#include "partition/evolution_search.hpp"
#include "util/input_error.hpp"

namespace tessera::partition_detail {

void IslandOptions::validate() const {
  if (islands < 1 || islands > 8)
    throw InputError("IslandOptions.islands = " + std::to_string(islands) + ": must be in 1..8");
  if (!(second_matching_share == -1.0 ||
        (second_matching_share >= 0.0 && second_matching_share <= 1.0)))
    throw InputError("IslandOptions.second_matching_share = " +
                     std::to_string(second_matching_share) + ": must be -1 or in 0..1");
  if (exchange_every < 0)
    throw InputError("IslandOptions.exchange_every = " + std::to_string(exchange_every) +
                     ": must be >= 0");
}

namespace {

// CPU time of the calling thread: the islands' own cost, which the process clock would add up.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

struct Island {
  Rng rng;
  std::unique_ptr<EvolutionSearch> search;
  double cpu_ms = 0.0;
  int taken = 0;  ///< Individuals from other islands that entered this population.
  std::exception_ptr error;
};

}  // namespace

IslandSearchResult island_search(
    const WorkGraph& g, int k, const std::vector<long long>& ub, const EvolutionParams& params,
    Rng& rng, const std::function<void(const std::string&, const std::string&, long long)>& trace) {
  params.islands.validate();
  const int count = params.islands.islands;
  // Island 0 runs on the caller's generator; the others get seeds drawn from a copy of it, so
  // the caller's stream (and island 0's search) is the one a single search would draw.
  Rng seeder = rng;
  const std::uint64_t base = seeder.next();
  EvolutionParams second = params;
  if (params.islands.second_matching_share >= 0.0)
    second.matching_share = params.islands.second_matching_share;
  std::vector<Island> islands;
  islands.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    islands.push_back(
        Island{i == 0 ? rng : Rng(base ^ (0xA24BAED4963EE407ULL * i)), nullptr, 0.0, 0, nullptr});
    islands.back().search =
        std::make_unique<EvolutionSearch>(g, k, ub, i == 1 ? second : params, islands.back().rng);
  }

  // One epoch: every island runs `job` on its own thread (island 0 on the caller's); joining
  // them all is the barrier after which individuals are exchanged.
  auto epoch = [&](auto job) {
    auto run_one = [&](Island& isl) {
      try {
        const double c0 = thread_cpu_ms();
        job(*isl.search);
        isl.cpu_ms += thread_cpu_ms() - c0;
      } catch (...) {
        isl.error = std::current_exception();
      }
    };
    std::vector<std::thread> threads;
    for (int i = 1; i < count; ++i) threads.emplace_back(run_one, std::ref(islands[i]));
    run_one(islands[0]);
    for (auto& t : threads) t.join();
    for (auto& isl : islands)
      if (isl.error) std::rethrow_exception(isl.error);
  };

  epoch([](EvolutionSearch& s) { s.build_population(); });
  if (trace) {
    long long cut = LLONG_MAX;
    for (auto& isl : islands) cut = std::min(cut, isl.search->best().cut);
    trace("population",
          (count > 1 ? std::to_string(count) + " islands x " : std::string()) +
              std::to_string(params.population) + " multilevel runs + " +
              std::to_string(params.vcycles) + " V-cycles each",
          cut);
  }

  const int chunk = params.islands.exchange_every > 0 ? params.islands.exchange_every : INT_MAX;
  auto running = [&] {
    for (auto& isl : islands)
      if (!isl.search->ended()) return true;
    return false;
  };
  while (running()) {
    epoch([chunk](EvolutionSearch& s) { s.run(chunk); });
    if (params.islands.exchange_every <= 0 || count < 2) continue;
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
      const std::string steps = std::to_string(s.steps()) + " combine/mutation steps, " +
                                std::to_string(s.improved()) + " improved the best";
      if (count == 1) {
        detail = steps;  // the single search's trace, as before the islands
        break;
      }
      detail += (i > 0 ? "; " : "") + ("island " + std::to_string(i) + ": ") + steps + ", " +
                std::to_string(islands[i].taken) + " migrants taken, best " +
                std::to_string(s.best().cut) + ", thread cpu " +
                std::to_string(static_cast<long long>(islands[i].cpu_ms)) + " ms";
    }
    if (count > 1) detail += "; winner island " + std::to_string(winner);
    trace("evolution", detail, result.cut);
  }
  // The caller's generator continues from island 0's state (the single search's stream).
  rng = islands[0].rng;
  return result;
}

}  // namespace tessera::partition_detail
