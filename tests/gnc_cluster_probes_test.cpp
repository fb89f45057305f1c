// Cluster probes of the centralized robust solve (GncCentralizedOptions::cluster_probes) and the
// clusters of kept closures they cut (closure_clusters.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tessera/robust/closure_clusters.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>

#include "gnc_fixtures.hpp"
#include "robust/cluster_probes.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

using test::flexible_city;

// A 2D chain of n poses (odometry only) to hang closures on; only the structure matters here.
PoseGraph chain(std::size_t n) {
  PoseGraph g;
  g.d = 2;
  g.num_poses = n;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    Measurement m;
    m.i = i;
    m.j = i + 1;
    m.R = Eigen::Matrix2d::Identity();
    m.t = Eigen::Vector2d(1, 0);
    m.kappa = m.tau = 1;
    g.measurements.push_back(m);
  }
  return g;
}

void add_closure(PoseGraph& g, std::size_t i, std::size_t j) {
  Measurement m = g.measurements.front();
  m.i = i;
  m.j = j;
  g.measurements.push_back(m);
}

std::vector<bool> odometry_flags(const PoseGraph& g) {
  std::vector<bool> known;
  for (const Measurement& m : g.measurements) known.push_back(m.j == m.i + 1 || m.i == m.j + 1);
  return known;
}

TEST(ClosureClusters, ARunSideBySideIsOneClusterAndOnlyCutClosuresNearItPointAtIt) {
  PoseGraph g = chain(200);
  const std::size_t first = g.num_measurements();
  for (std::size_t k = 0; k < 5; ++k) add_closure(g, 10 + k, 100 + k);  // a run, one id apart
  add_closure(g, 107, 16);   // beside the run (written high to low): 2 and 3 ids from its ends
  add_closure(g, 60, 160);   // alone: no cluster
  add_closure(g, 150, 190);  // a second run of two, far from everything
  add_closure(g, 152, 192);
  add_closure(g, 20, 110);  // rejected, 5 ids from the first run's stretches
  const std::size_t cut = g.num_measurements() - 1;
  const std::vector<bool> known = odometry_flags(g);

  EXPECT_TRUE(closure_clusters(g, known, {}, ClosureClusterOptions{}).empty())
      << "nothing rejected: nothing points at a cluster";
  ClosureClusterOptions o;
  o.near = 10;
  std::vector<ClosureCluster> c = closure_clusters(g, known, {cut}, o);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].members,
            (std::vector<std::size_t>{first, first + 1, first + 2, first + 3, first + 4}));
  EXPECT_EQ(c[0].rejected_near, 1u);
  o.near = 0;  // the cut closure no longer lies near the run
  EXPECT_TRUE(closure_clusters(g, known, {cut}, o).empty());
  o.window = 3;  // (107, 16) joins the run: its ends are within 3 ids of the last member
  o.near = 10;
  c = closure_clusters(g, known, {cut}, o);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].members.size(), 6u);
}

TEST(ClosureClusters, ARunGncPartlyCutComesFirstThenTheLongestThenTheOneMoreCutClosuresPointAt) {
  PoseGraph g = chain(400);
  const std::size_t pair = g.num_measurements();
  add_closure(g, 10, 100);  // a pair with three cut closures beside it
  add_closure(g, 11, 101);
  const std::size_t run = g.num_measurements();
  for (std::size_t k = 0; k < 6; ++k) add_closure(g, 200 + k, 300 + k);  // a run of six
  const std::size_t other_pair = g.num_measurements();
  add_closure(g, 150, 250);  // a second pair, one cut closure beside it
  add_closure(g, 151, 251);
  std::vector<std::size_t> cut;
  for (std::size_t i : {20u, 22u, 24u}) {
    add_closure(g, i, 380);
    cut.push_back(g.num_measurements() - 1);
  }
  add_closure(g, 210, 390);  // near the run: one cut closure
  cut.push_back(g.num_measurements() - 1);
  add_closure(g, 160, 395);  // near the second pair
  cut.push_back(g.num_measurements() - 1);
  const std::size_t partly_cut = g.num_measurements();
  add_closure(g, 60, 120);  // a pair whose run goes on in a cut closure
  add_closure(g, 61, 121);
  add_closure(g, 62, 122);
  cut.push_back(g.num_measurements() - 1);
  std::sort(cut.begin(), cut.end());

  const std::vector<ClosureCluster> c =
      closure_clusters(g, odometry_flags(g), cut, ClosureClusterOptions{});
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0].members.front(), partly_cut) << "GNC cut the rest of its run: first";
  EXPECT_EQ(c[0].rejected_in_run, 1u);
  EXPECT_EQ(c[1].members.front(), run) << "a longer run holds a bend more firmly: next";
  EXPECT_EQ(c[1].members.size(), 6u);
  EXPECT_EQ(c[1].rejected_in_run, 0u);
  EXPECT_EQ(c[2].members.front(), pair) << "then, among equals, the most cut closures near";
  EXPECT_EQ(c[2].rejected_near, 3u);
  EXPECT_EQ(c[3].members.front(), other_pair);
}

TEST(ClosureClusters, PartlyCutRunsAreOneProbeOnlyWhenThereAreTwoOrMore) {
  ClosureCluster one, two, whole;
  one.members = {5, 9};
  one.rejected_in_run = 1;
  two.members = {2, 7};
  two.rejected_in_run = 2;
  whole.members = {1, 3};
  EXPECT_TRUE(partly_cut_runs({one, whole}).members.empty()) << "one run is a single probe";
  const ClusterUnion both = partly_cut_runs({whole, one, two});
  EXPECT_EQ(both.members, (std::vector<std::size_t>{2, 5, 7, 9}));
  ASSERT_EQ(both.parts.size(), 2u);
  EXPECT_EQ(both.parts[0].members, one.members);
}

TEST(ClosureClusters, BadOptionsNameTheField) {
  const PoseGraph g = chain(10);
  ClosureClusterOptions o;
  o.window = 0;
  const std::string e =
      test::input_error_of([&] { closure_clusters(g, odometry_flags(g), {}, o); });
  EXPECT_NE(e.find("ClosureClusterOptions.window"), std::string::npos) << e;
  GncCentralizedOptions gnc;
  gnc.cluster_probes = -1;
  EXPECT_TRUE(test::validation_names(gnc, "GncCentralizedOptions.cluster_probes"));
  gnc.cluster_probes = 1;
  gnc.robust.probe_return_ratio = 0.5;
  EXPECT_TRUE(test::validation_names(gnc, "RobustOptions.probe_return_ratio"));
}

// Return probes (RobustOptions::probe_return_ratio): the rejected closures just beyond the bound
// come back together first, then one at a time nearest first; a far one never does. On a 20-pose
// chain, closure A (0-5) is at 2 c^2, B (10-15) at 3 c^2, C (12-18) at 10 c^2. The solve is a
// stand-in: when A is back it returns poses stretched so that A fits (the odometry takes a
// fifth of A's residual), and the re-check verdict there as its rejected set.
TEST(ClusterProbes, AReturnProbeBringsBackTheClosuresJustBeyondTheBoundAndKeepsWhatLowersTheTls) {
  PoseGraph g = chain(20);
  std::vector<Pose> poses(20);
  for (std::size_t i = 0; i < 20; ++i) {
    poses[i].R = Eigen::Matrix2d::Identity();
    poses[i].t = Eigen::Vector2d(static_cast<double>(i), 0);
  }
  const double delta = 1.0;
  auto closure = [&](std::size_t i, std::size_t j, double offset) {
    add_closure(g, i, j);
    g.measurements.back().t = Eigen::Vector2d(static_cast<double>(j - i) + offset, 0);
    return g.num_measurements() - 1;
  };
  const std::size_t a = closure(0, 5, delta), b = closure(10, 15, delta * std::sqrt(1.5)),
                    c = closure(12, 18, delta * std::sqrt(5.0));
  const std::vector<bool> known = odometry_flags(g);
  const Measurement& ma = g.measurements[a];
  const double c2 = residual_squared(ma, poses[ma.i], poses[ma.j]) / 2;
  std::vector<Pose> stretched = poses;
  for (std::size_t i = 0; i <= 5; ++i) stretched[i].t.x() -= delta * static_cast<double>(5 - i) / 5;
  const std::vector<std::size_t> all = {a, b, c};
  EXPECT_EQ(return_candidates(g, poses, c2, 4.0, all), (std::vector<std::size_t>{a, b}));

  std::vector<std::vector<std::size_t>> asked;
  auto solve = [&](std::vector<std::size_t> rejected) {
    asked.push_back(rejected);
    const bool a_back = !std::binary_search(rejected.begin(), rejected.end(), a);
    const std::vector<Pose>& at = a_back ? stretched : poses;
    return ClusterProbeTrial{tls_recheck(g, known, at, c2, rejected).rejected, at};
  };
  int kept_calls = 0;
  ProbeRules rules;
  rules.budget = 10;
  rules.return_ratio = 4.0;
  const ClusterProbeCounts counts =
      search_cluster_probes(g, known, c2, rules, all, poses, solve, [&] { ++kept_calls; });
  // Together (A and B back): A fits, the passes cut B again, the TLS cost falls: kept. Then B
  // alone at the new solution: nothing changes, refused. C is never asked back.
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_EQ(asked[0], (std::vector<std::size_t>{c}));
  EXPECT_EQ(asked[1], (std::vector<std::size_t>{c}));
  EXPECT_EQ(counts.probes, 2);
  EXPECT_EQ(counts.kept, 1);
  EXPECT_EQ(kept_calls, 1);
  EXPECT_EQ(counts.returned, 1u) << "A stays back, B was cut again";
}

// The case cluster probes exist for: on a map whose information states more noise than its data
// has, GNC bends the map until whole groups of mutually consistent wrong closures fit, and cuts
// the true closures of those stretches instead; the re-check passes judge one closure at a time
// and keep the groups. A probe cuts a group at once, the passes take the true closures back, and
// the TLS cost falls, so it stays: every wrong closure found, nothing else, at the clean cost.
TEST(GncCentralized, ClusterProbesCutAGroupOfConsistentWrongClosuresThatGncAloneKeeps) {
  const GeneratorResult g = flexible_city(0.1, OutlierKind::kGroup, 3);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.robust.probe_tail_ratio = 1e9;  // no tail probe (the next test has it)
  const GncCentralizedResult without = solve_gnc_centralized(g.graph, o);
  o.cluster_probes = 20;
  const GncCentralizedResult with = solve_gnc_centralized(g.graph, o);

  auto found = [&](const GncCentralizedResult& r) {
    std::size_t hit = 0;
    for (std::size_t e : r.rejected)
      hit += std::binary_search(g.outliers.begin(), g.outliers.end(), e) ? 1 : 0;
    return hit;
  };
  // Without cluster probes only the return probe (at most one) may run.
  EXPECT_LE(without.probes, 1);
  EXPECT_LT(found(without), g.outliers.size() - 5) << "GNC alone keeps a group";
  EXPECT_GE(with.probes_kept, 1);
  EXPECT_LE(with.probes, 20 + 1);
  EXPECT_EQ(with.rejected, g.outliers);
  // Every kept measurement is within the bound at the end, so the TLS cost is the kept cost plus
  // c^2 per rejected measurement; the probes only ever lower it.
  auto tls = [](const GncCentralizedResult& r) {
    return r.final_solve.cost + r.threshold_squared * static_cast<double>(r.rejected.size());
  };
  EXPECT_LT(tls(with), tls(without));
  EXPECT_TRUE(with.final_solve.certified.value_or(false));
  for (std::size_t e = 0; e < with.weights.size(); ++e)
    EXPECT_EQ(with.weights[e],
              std::binary_search(with.rejected.begin(), with.rejected.end(), e) ? 0.0 : 1.0);
}

// The tail probe (RobustOptions::probe_ratio, probe_tail_ratio; on by default): the same bent map
// has a heavy tail of kept residuals (the closures the bend fits lie far above the median), so
// the kept closures above 5 x the median leave together, the passes take back the true closures
// that fit without them, and the TLS cost falls: it stays, and every wrong closure is found
// without cluster probes.
TEST(GncCentralized, ATailProbeCutsTheClosuresABentMapFitsAndStaysWhenTheTlsCostFalls) {
  const GeneratorResult g = flexible_city(0.1, OutlierKind::kGroup, 3);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.robust.probe_tail_ratio = 1e9;  // the tail rule never holds: no tail probe
  const GncCentralizedResult without = solve_gnc_centralized(g.graph, o);
  o.robust.probe_tail_ratio = RobustOptions{}.probe_tail_ratio;
  const GncCentralizedResult with = solve_gnc_centralized(g.graph, o);
  EXPECT_NE(without.rejected, g.outliers);
  EXPECT_EQ(with.rejected, g.outliers);
  EXPECT_GE(with.probes_kept, 1);
  EXPECT_LE(with.probes, RobustOptions{}.recheck_probes + 1);
  auto tls = [](const GncCentralizedResult& r) {
    return r.final_solve.cost + r.threshold_squared * static_cast<double>(r.rejected.size());
  };
  EXPECT_LT(tls(with), tls(without));
  EXPECT_TRUE(with.final_solve.certified.value_or(false));
  // With probes off (--gnc-probes 0) neither kind runs.
  o.robust.recheck_probes = 0;
  EXPECT_EQ(solve_gnc_centralized(g.graph, o).probes, 0);
}

// Where GNC alone already finds every wrong closure, refused probes change nothing.
TEST(GncCentralized, ClusterProbesLeaveAnExactAnswerAsItIs) {
  const GeneratorResult g = flexible_city(0.1, OutlierKind::kGroup, 1);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  const GncCentralizedResult without = solve_gnc_centralized(g.graph, o);
  o.cluster_probes = 5;
  const GncCentralizedResult with = solve_gnc_centralized(g.graph, o);
  EXPECT_EQ(without.rejected, g.outliers);
  EXPECT_EQ(with.probes, 5);
  EXPECT_EQ(with.probes_kept, 0);
  EXPECT_EQ(with.rejected, without.rejected);
  EXPECT_EQ(with.final_solve.cost, without.final_solve.cost);
}

TEST(GncClusterProbesCli, TheFlagReachesTheSolveAndABadValueNamesItWithExitStatusTwo) {
  const std::string dir = test::temp_dir();
  const std::string file = dir + "/group.g2o", json = dir + "/out.json";
  std::string output;
  ASSERT_EQ(test::run_command(test::bin("tessera") +
                                  " generate --kind grid3d --poses 125 --robots 5 --seed 2 "
                                  "--outliers 0.25 --outlier-kind group --out " +
                                  file,
                              &output),
            0)
      << output;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + file +
                                  " --robust gnc-tls --gnc-cluster-probes -1",
                              &output),
            2);
  EXPECT_TRUE(test::contains(output, "--gnc-cluster-probes")) << output;
  EXPECT_TRUE(test::contains(output, "GncCentralizedOptions.cluster_probes")) << output;
  ASSERT_EQ(test::run_command(test::bin("tessera") + " solve " + file +
                                  " --robust gnc-tls --gnc-cluster-probes 2 --json " + json,
                              &output),
            0)
      << output;
  const std::string summary = test::read_text_file(json);
  // Rejected closures lie near kept runs of the grid, so the budget of 2 is what ends the probes.
  EXPECT_TRUE(test::contains(summary, "\"probes\": 2")) << summary;
}

}  // namespace
}  // namespace tessera
