// Swap probes of the centralized robust solve (RobustOptions::swap_probes, swap_probe.hpp) and
// the verdict that ends every probe (probe_outcome.hpp): a probe whose passes take back exactly
// what it cut ends not kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/robust_options.hpp>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <vector>

#include "gnc_fixtures.hpp"
#include "robust/gnc_probes.hpp"
#include "robust/probe_outcome.hpp"
#include "robust/swap_probe.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// A fold on a 20-pose 2D chain along x (unit odometry, known inliers; kappa = tau = 1, c^2 = 1):
// the wrong closure W (5-15) measures 10 + delta - eps, the true closure T (5-10) measures 5, the
// true closure K (2-5) measures 3 + eta. Two stand-in solutions: `bent`, poses 10.. shifted by
// delta (odometry 9-10 at 3 c^2, T at 3 c^2, W at 0.5 c^2), and `relaxed`, the straight chain (T
// at 0, W at 1.05 c^2). K is at 0.9 c^2 in both. At `bent` W fits and T is cut: GNC's fold.
struct Fold {
  PoseGraph graph;
  std::vector<bool> known;
  std::vector<Pose> bent, relaxed;
  std::size_t w = 0, t = 0, k = 0;
  const double c2 = 1.0;
};

Fold make_fold() {
  Fold f;
  PoseGraph& g = f.graph;
  g.d = 2;
  g.num_poses = 20;
  auto add = [&](std::size_t i, std::size_t j, double dx) {
    Measurement m;
    m.i = i;
    m.j = j;
    m.R = Eigen::Matrix2d::Identity();
    m.t = Eigen::Vector2d(dx, 0);
    m.kappa = m.tau = 1;
    g.measurements.push_back(m);
    f.known.push_back(j == i + 1);
    return g.measurements.size() - 1;
  };
  for (std::size_t i = 0; i + 1 < 20; ++i) add(i, i + 1, 1.0);
  const double delta = std::sqrt(3.0), eps = std::sqrt(0.5), eta = std::sqrt(0.9);
  f.k = add(2, 5, 3 + eta);
  f.t = add(5, 10, 5);
  f.w = add(5, 15, 10 + delta - eps);
  for (std::size_t i = 0; i < 20; ++i) {
    Pose p;
    p.R = Eigen::Matrix2d::Identity();
    p.t = Eigen::Vector2d(static_cast<double>(i), 0);
    f.relaxed.push_back(p);
    if (i >= 10) p.t.x() += delta;
    f.bent.push_back(p);
  }
  return f;
}

// The stand-in for the kept set's solve with its re-check passes: while W is in, the map stays
// bent; without it, it relaxes; the set is TLS's verdict there.
ClusterProbeTrial stand_in_solve(const Fold& f, const std::vector<std::size_t>& rejected) {
  const bool w_cut = std::binary_search(rejected.begin(), rejected.end(), f.w);
  const std::vector<Pose>& at = w_cut ? f.relaxed : f.bent;
  return ClusterProbeTrial{tls_recheck(f.graph, f.known, at, f.c2, rejected).rejected, at};
}

TEST(SwapProbes, TheCandidatesAreTheStrainedKeptClosuresBesideARejectedOneNearTheBound) {
  const Fold f = make_fold();
  SwapRules rules;
  rules.budget = 3;
  const std::vector<ClosureSwap> swaps =
      swap_candidates(f.graph, f.known, f.bent, f.c2, rules, {f.t});
  // K (0.9 c^2) before W (0.5 c^2), both share pose 5 with T (3 c^2 <= 10 c^2).
  ASSERT_EQ(swaps.size(), 2u);
  EXPECT_EQ(swaps[0].cut, f.k);
  EXPECT_EQ(swaps[0].back, f.t);
  EXPECT_EQ(swaps[1].cut, f.w);
  EXPECT_EQ(swaps[1].back, f.t);
  rules.kept_ratio = 0.6;  // W is no longer strained enough
  EXPECT_EQ(swap_candidates(f.graph, f.known, f.bent, f.c2, rules, {f.t}).size(), 1u);
  rules.return_ratio = 2;  // T lies beyond 2 c^2
  EXPECT_TRUE(swap_candidates(f.graph, f.known, f.bent, f.c2, rules, {f.t}).empty());

  // Nothing rejected: no pair, but a kept closure far above the kept median (T: 3 c^2 against
  // 0.9 c^2) is cut alone when alone_ratio allows it.
  rules = SwapRules{};
  EXPECT_TRUE(swap_candidates(f.graph, f.known, f.bent, f.c2, rules, {}).empty());  // 5 x 0.9
  rules.alone_ratio = 2;
  const std::vector<ClosureSwap> alone = swap_candidates(f.graph, f.known, f.bent, f.c2, rules, {});
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone[0].cut, f.t);
  EXPECT_FALSE(alone[0].back.has_value());
}

// The fold: swapping K for T keeps the bend (W holds it), the passes cut T again and take K
// back, so the set is the base's: not kept. Swapping W for T relaxes the map, the TLS cost falls
// from 5.4 c^2 to 1.9 c^2: kept. From there, swapping K for W bends the map again: refused.
TEST(SwapProbes, ASwapThatLowersTheTlsCostIsKeptAndOneThatDoesNotIsUndone) {
  const Fold f = make_fold();
  EXPECT_NEAR(tls_cost(f.graph, f.known, f.bent, f.c2), 5.4, 1e-9);
  EXPECT_NEAR(tls_cost(f.graph, f.known, f.relaxed, f.c2), 1.9, 1e-9);
  std::vector<std::vector<std::size_t>> asked, ended;
  std::vector<std::size_t> adopted;
  ClusterProbeTrial last;
  SwapRules rules;
  rules.budget = 3;
  const SwapProbeCounts counts = search_swap_probes(
      f.graph, f.known, f.c2, rules, {f.t}, f.bent,
      [&](std::vector<std::size_t> rejected) {
        asked.push_back(rejected);
        last = stand_in_solve(f, rejected);
        ended.push_back(last.rejected);
        return last;
      },
      [&] { adopted = last.rejected; });
  ASSERT_EQ(asked.size(), 3u);
  EXPECT_EQ(asked[0], (std::vector<std::size_t>{f.k}));  // K out, T back
  EXPECT_EQ(ended[0], (std::vector<std::size_t>{f.t}));  // ... and the passes undo it
  EXPECT_EQ(asked[1], (std::vector<std::size_t>{f.w}));  // W out, T back
  EXPECT_EQ(ended[1], (std::vector<std::size_t>{f.w}));
  EXPECT_EQ(asked[2], (std::vector<std::size_t>{f.k}));  // K out, W back: bent again
  EXPECT_EQ(counts.probes, 3);
  EXPECT_EQ(counts.kept, 1);
  EXPECT_EQ(adopted, (std::vector<std::size_t>{f.w}));

  rules.budget = 0;
  int solves = 0;
  EXPECT_EQ(search_swap_probes(
                f.graph, f.known, f.c2, rules, {f.t}, f.bent,
                [&](std::vector<std::size_t> r) {
                  ++solves;
                  return stand_in_solve(f, r);
                },
                [] {})
                .probes,
            0);
  EXPECT_EQ(solves, 0);
}

// A probe whose passes put the set back where it started ends not kept, even when the TLS cost
// at its end is lower: the two costs belong to the same set solved twice (probe_outcome.hpp).
TEST(ProbeOutcome, AProbeWhosePassesTakeBackExactlyWhatItCutEndsNotKept) {
  const std::vector<std::size_t> base = {3, 8};
  EXPECT_EQ(probe_outcome(base, 100.0, base, 50.0, 1e-6), ProbeOutcome::kBackAtBase);
  EXPECT_EQ(probe_outcome(base, 100.0, {3}, 50.0, 1e-6), ProbeOutcome::kKept);
  EXPECT_EQ(probe_outcome(base, 100.0, {3}, 100.0 - 1e-3, 1e-6), ProbeOutcome::kKept);
  EXPECT_EQ(probe_outcome(base, 100.0, {3}, 100.0 - 1e-5, 1e-6), ProbeOutcome::kRefused);
  EXPECT_EQ(probe_outcome(base, 100.0, {3, 8, 9}, 101.0, 1e-6), ProbeOutcome::kRefused);

  // Distributed: a pass whose verdict is the base's set ends the running probe, not kept.
  GncProbes probes(2);
  ASSERT_TRUE(probes.may_start(true, 10));
  GncProbeBase b;
  b.tls = 100;
  b.rejected = {3, 8};
  probes.start(b);
  EXPECT_FALSE(probes.back_at_base({3, 5, 8}));  // the cut (5) still out
  EXPECT_TRUE(probes.back_at_base({3, 8}));      // it came back
  EXPECT_FALSE(probes.keeps({3, 8}, 50.0)) << "the base's set: not kept whatever its cost";
  EXPECT_EQ(probes.kept(), 0);
  probes.start(b);
  EXPECT_TRUE(probes.keeps({3, 5, 8}, 50.0));
  EXPECT_EQ(probes.kept(), 1);
  EXPECT_FALSE(probes.back_at_base({3, 8})) << "no probe running";

  // Centralized: the stand-in's passes put the fold's set back (W is kept, T cut again), but at
  // poses with a lower TLS cost than the base's: the swap is still not kept.
  const Fold f = make_fold();
  SwapRules rules;
  rules.budget = 1;
  int kept_calls = 0;
  const SwapProbeCounts counts = search_swap_probes(
      f.graph, f.known, f.c2, rules, {f.t}, f.bent,
      [&](std::vector<std::size_t>) {
        return ClusterProbeTrial{{f.t}, f.relaxed};
      },
      [&] { ++kept_calls; });
  EXPECT_LT(tls_cost(f.graph, f.known, f.relaxed, f.c2), tls_cost(f.graph, f.known, f.bent, f.c2));
  EXPECT_EQ(counts.probes, 1);
  EXPECT_EQ(counts.kept, 0);
  EXPECT_EQ(kept_calls, 0);
}

// The same rule in the distributed engine: with a ratio of 1.5 and no tail rule, a probe cuts
// half the true closures of the 125-pose grid, the first pass takes every one of them back, and
// the probe ends there, not kept: the set from before the probe, the clean optimum, certified.
TEST(GncDistributed, AProbeWhosePassesTakeBackExactlyWhatItCutEndsNotKept) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o = test::irbcd_gnc();
  o.solver.certify = true;
  o.robust.probe_ratio = 1.5;
  o.robust.probe_tail_ratio = 0;
  o.robust.recheck_probes = 1;
  o.robust.probe_cut = ProbeCut::kAlways;  // the passes leave GNC's set alone here
  const GncDistributedResult r =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  EXPECT_EQ(r.probes, 1);
  EXPECT_EQ(r.probes_kept, 0);
  EXPECT_EQ(r.rejected, dirty.outliers);
  EXPECT_TRUE(r.final_solve.certified.value_or(false));
}

TEST(SwapProbes, BadSwapOptionsNameTheField) {
  RobustOptions o;
  o.swap_probes = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.swap_probes"));
  o = RobustOptions{};
  o.swap_near = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.swap_near"));
  o = RobustOptions{};
  o.swap_kept_ratio = 1.5;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.swap_kept_ratio"));
  o = RobustOptions{};
  o.swap_return_ratio = 0.5;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.swap_return_ratio"));
}

}  // namespace
}  // namespace tessera
