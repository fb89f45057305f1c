// Cluster probes of the distributed robust solve (GncDistributedOptions::cluster_probes): the
// search every agent runs alike (core/robust/gnc_cluster_search.hpp) and what it finds.
#include <gtest/gtest.h>

#include <algorithm>
#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"
#include "robust/gnc_cluster_search.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

using test::flexible_city;
using test::robots_as_blocks;

using Ids = std::vector<std::uint64_t>;

// A chain of n poses (odometry, known inliers) and closures on it; only endpoints matter here.
struct Chain {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  std::vector<bool> known;
  explicit Chain(std::uint32_t n) {
    for (std::uint32_t i = 0; i + 1 < n; ++i) add(i, i + 1, true);
  }
  std::uint64_t add(std::uint32_t i, std::uint32_t j, bool is_known = false) {
    structure.emplace_back(i, j);
    known.push_back(is_known);
    return structure.size() - 1;
  }
};

TEST(GncClusterSearch, TriesTheTailThenEachClusterThenTheReturnBandTogetherThenAlone) {
  Chain c(200);
  const std::uint64_t run0 = c.add(10, 100), run1 = c.add(11, 101), run2 = c.add(12, 102);
  const std::uint64_t tail = c.add(60, 160);                             // kept, alone
  const std::uint64_t cut = c.add(20, 110);                              // rejected near the run
  const std::uint64_t near_a = c.add(40, 140), near_b = c.add(45, 180);  // rejected, the band
  const Ids rejected = {cut, near_a, near_b};
  GncClusterSearch search(c.structure, c.known, /*tail_budget=*/1, /*budget=*/10, {});
  search.set_list({near_b, tail, near_a}, {near_b, tail, near_a});

  EXPECT_EQ(search.next(rejected), (Ids{tail, near_a, near_b})) << "the agents' tail probe";
  search.refused(5.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{run0, run1, run2})) << "the run the cut closure points at";
  search.refused(5.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{near_a, near_b})) << "no cluster left: the band together";
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{near_a}));
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{near_b}));
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), std::nullopt) << "everything tried since the set changed";
  EXPECT_EQ(search.tail_probes(), 1);
  EXPECT_EQ(search.probes(), 4);

  // A kept probe changes the set: every candidate may be tried again (the tail budget is spent),
  // and the band together comes first, since a cut fold lets its true closures back in.
  search.kept();
  search.set_list({near_a, near_b}, {near_a, near_b});
  EXPECT_EQ(search.next(rejected), (Ids{near_a, near_b})) << "a probe stayed: the band first";
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{run0, run1, run2}));
}

TEST(GncClusterSearch, EveryRunGncPartlyCutIsCutTogetherFirstThenOneRunAtATime) {
  Chain c(300);
  const std::uint64_t a0 = c.add(10, 100), a1 = c.add(11, 101), cut_a = c.add(12, 102);
  const std::uint64_t b0 = c.add(150, 250), b1 = c.add(151, 251), cut_b = c.add(152, 252);
  Ids longer;  // a longer run, wholly kept, with a cut closure near it
  for (std::uint32_t k = 0; k < 5; ++k) longer.push_back(c.add(50 + k, 200 + k));
  const std::uint64_t near_longer = c.add(60, 280);
  Ids rejected = {cut_a, cut_b, near_longer};
  std::sort(rejected.begin(), rejected.end());
  GncClusterSearch search(c.structure, c.known, /*tail_budget=*/0, /*budget=*/10, {});
  search.set_list({}, {});

  EXPECT_EQ(search.next(rejected), (Ids{a0, a1, b0, b1}))
      << "runs that share one bend may only leave together";
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{a0, a1})) << "then each partly cut run";
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), (Ids{b0, b1}));
  search.refused(1.0, 100.0);
  EXPECT_EQ(search.next(rejected), longer) << "then the longer runs";
}

TEST(GncClusterSearch, TheTailProbeFlipsWhatTheStageGivesIt) {
  Chain c(200);
  c.add(10, 100);
  c.add(11, 101);
  const std::uint64_t tail = c.add(60, 160);  // kept, named by an agent's tail
  const std::uint64_t band = c.add(40, 140);  // rejected, in the return band
  GncClusterSearch search(c.structure, c.known, /*tail_budget=*/1, /*budget=*/10, {});
  // Where GNC's own set keeps its tail (GncProbeStage::flips), only the band comes back.
  search.set_list({tail, band}, {band});
  EXPECT_EQ(search.next({band}), (Ids{band}));
  EXPECT_EQ(search.tail_probes(), 1);
  EXPECT_EQ(search.probes(), 0);
}

TEST(GncClusterSearch, TheBudgetBoundsTheClusterAndReturnProbes) {
  Chain c(200);
  const std::uint64_t run0 = c.add(10, 100), run1 = c.add(11, 101);
  const std::uint64_t cut = c.add(20, 110);
  GncClusterSearch search(c.structure, c.known, 0, 1, {});
  search.set_list({cut}, {});
  EXPECT_EQ(search.next({cut}), (Ids{run0, run1}));
  search.refused(1.0, 10.0);
  EXPECT_EQ(search.next({cut}), std::nullopt) << "budget of one spent";
}

TEST(GncDistributedOptions, ABadClusterOptionNamesTheField) {
  GncDistributedOptions o;
  o.cluster_probes = -1;
  EXPECT_TRUE(test::validation_names(o, "GncDistributedOptions.cluster_probes"));
  o.cluster_probes = 3;
  o.clusters.window = 0;
  EXPECT_TRUE(test::validation_names(o, "ClosureClusterOptions.window"));
}

// The case the cluster probes exist for, distributed: on a map whose information states more
// noise than its data has, GNC bends the map until groups of mutually consistent wrong closures
// fit and cuts true closures of those stretches instead; the agents' tail probes cut by their own
// residual tails and leave groups in. A cluster probe cuts one group at once, the passes take the
// true closures back, the summed TLS cost falls and the probe stays: exactly the wrong closures.
TEST(GncDistributed, ClusterProbesRejectExactlyTheGroupsTheAgentsProbesKeep) {
  const GeneratorResult g = flexible_city(0.1, OutlierKind::kGroup, 3);
  const std::vector<int> blocks = robots_as_blocks(g);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  // GNC's solves by rounds: with Newton steps (RobustOptions::gnc_refine_steps) GNC alone finds
  // exactly these groups here, and there is nothing left for the cluster probes to show.
  o.robust.refine_passes = false;
  // After the plain solve's rounds: weighed at the voted start (RobustOptions::weigh_at_start)
  // GNC alone finds exactly these groups here too.
  o.robust.weigh_at_start = false;
  const GncDistributedResult without = solve_gnc_distributed(g.graph, blocks, o);
  o.cluster_probes = 20;
  const GncDistributedResult with = solve_gnc_distributed(g.graph, blocks, o);

  EXPECT_NE(without.rejected, g.outliers) << "the agents' probes alone keep a group";
  EXPECT_EQ(with.rejected, g.outliers);
  EXPECT_GE(with.probes_kept, 1);
  EXPECT_LE(with.probes, RobustOptions{}.recheck_probes + 20);
  // Every kept measurement is within the bound at the end: TLS cost = kept cost + c^2 per
  // rejected measurement; kept probes only lower it.
  auto tls = [](const GncDistributedResult& r) {
    return r.final_solve.cost + r.threshold_squared * static_cast<double>(r.rejected.size());
  };
  EXPECT_LT(tls(with), tls(without));
  EXPECT_TRUE(with.final_solve.certified.value_or(false));
  // Each weight as its owner holds it: 0 exactly for the rejected set.
  for (std::size_t e = 0; e < with.weights.size(); ++e)
    EXPECT_EQ(with.weights[e] < 0.5,
              std::binary_search(with.rejected.begin(), with.rejected.end(), e))
        << e;
}

// Every agent picks the same probe from the same data whatever order its messages arrive in (as
// over DDS): a shuffled delivery runs the same probes to the same end.
TEST(GncDistributed, ClusterProbesDoNotDependOnTheDeliveryOrder) {
  const GeneratorResult g = flexible_city(0.1, OutlierKind::kGroup, 3);
  const std::vector<int> blocks = robots_as_blocks(g);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.cluster_probes = 20;
  const GncDistributedResult fifo = solve_gnc_distributed(g.graph, blocks, o);
  o.solver.delivery = DeliveryOrder::kShuffled;
  o.solver.delivery_seed = 5;
  const GncDistributedResult shuffled = solve_gnc_distributed(g.graph, blocks, o);
  EXPECT_GT(fifo.probes, RobustOptions{}.recheck_probes) << "the cluster search ran";
  EXPECT_EQ(shuffled.probes, fifo.probes);
  EXPECT_EQ(shuffled.probes_kept, fifo.probes_kept);
  EXPECT_EQ(shuffled.rejected, fifo.rejected);
  EXPECT_EQ(shuffled.total_rounds, fifo.total_rounds);
  EXPECT_EQ(shuffled.final_solve.cost, fifo.final_solve.cost);
}

}  // namespace
}  // namespace tessera
