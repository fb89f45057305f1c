// RobustOptions::jump_band (the early end of the distributed GNC): once no residual lies near the
// bound, GNC ends at TLS's verdict at that iterate and the passes follow; the same answer in
// fewer outer steps, both ends of every cut measurement with the same weight, no end while a
// closure beyond the bound still has weight at mu (RobustOptions::jump_band_max), the
// option's range, and the verdict weight as a function of the transmitted weight alone.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <utility>
#include <vector>

#include "gnc_fixtures.hpp"
#include "robust/gnc_votes.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(GncJump, ABadBandNamesTheField) {
  RobustOptions o;
  o.jump_band = 1.0;  // a band of width 0 around c^2
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.jump_band"));
  o.jump_band = 0;  // off
  EXPECT_NO_THROW(o.validate());
  o.jump_band = 1.5;
  EXPECT_NO_THROW(o.validate());
  o.jump_band_max = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.jump_band_max"));
  o.jump_band_max = 0;  // the band stays jump_band's
  EXPECT_NO_THROW(o.validate());
}

TEST(GncJump, TheVerdictWeightIsOneExactlyWithinTheBound) {
  // The other end of a cut measurement holds only the weight at mu it was sent: the verdict
  // taken from that weight must be the verdict of the residual itself.
  const double c2 = 33.0;
  for (double mu : {1e-4, 0.01, 0.3, 0.9}) {
    for (double ratio : {0.05, 0.4, 0.9, 0.999, 1.001, 1.5, 3.0, 1e3}) {
      const double w = tls_weight(ratio * c2, c2, mu);
      EXPECT_EQ(tls_verdict_weight(w, mu), ratio <= 1 ? 1.0 : 0.0)
          << "mu " << mu << ", r^2 = " << ratio << " c^2, w " << w;
    }
  }
}

// The 300-pose soft city with 25 % random outliers, 5 agents: 4 outer steps and 146 rounds in all
// against 10 and 181 with the weights left to become binary, the same rejected set and cost.
TEST(GncJump, GncEndsWhenTheResidualsLeaveTheBoundWithTheSameSetInFewerOuterSteps) {
  const GeneratorResult dirty = test::flexible_city(0.25, OutlierKind::kRandom, 1);
  const std::vector<int> blocks = test::robots_as_blocks(dirty);
  GncDistributedOptions o = test::irbcd_gnc();
  o.solver.certify = true;
  // The band of jump_band alone: on this soft map (information x 0.03) random wrong closures stay
  // within 30 c^2 to the end, so the band widened at small mu (jump_band_max) ends nothing early.
  o.robust.jump_band_max = 0;
  o.robust.jump_band = 0;
  const GncDistributedResult full = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.jump_band = 2;
  // (outer step, measurement) -> weight at each agent that holds it.
  std::map<std::pair<int, std::uint64_t>, std::map<int, double>> seen;
  o.weight_observer = [&](int agent, int outer, const std::vector<std::uint64_t>& index,
                          const std::vector<double>& weights) {
    for (std::size_t k = 0; k < index.size(); ++k) seen[{outer, index[k]}][agent] = weights[k];
  };
  const GncDistributedResult jumped = solve_gnc_distributed(dirty.graph, blocks, o);
  EXPECT_EQ(full.rejected, dirty.outliers);
  EXPECT_EQ(jumped.rejected, dirty.outliers);
  EXPECT_LT(jumped.outer_iterations, full.outer_iterations);
  EXPECT_LT(jumped.total_rounds, full.total_rounds);
  EXPECT_NEAR(jumped.final_solve.cost, full.final_solve.cost, 1e-8 * full.final_solve.cost);
  EXPECT_TRUE(jumped.final_solve.certified.value_or(false));
  // The last weights, after the jump, are binary and the same on both ends of every cut one.
  std::size_t last_cut = 0;
  for (const auto& [key, at] : seen) {
    if (key.first != jumped.outer_iterations) continue;
    for (const auto& [agent, w] : at) EXPECT_TRUE(w == 0 || w == 1) << "measurement " << key.second;
    if (at.size() < 2) continue;
    ++last_cut;
    EXPECT_EQ(at.begin()->second, at.rbegin()->second) << "measurement " << key.second;
  }
  EXPECT_GT(last_cut, 0u);
}

// RobustOptions::jump_band_inside false (`--gnc-jump-side beyond`): only residuals beyond the
// bound, in (c^2, B c^2), hold the early end back; those just within it are judged by the passes
// on the kept set itself. Against both sides of the band, on the soft city and the 125-pose grid
// with 25 % random outliers: the same rejected set (exactly the wrong closures) and certified
// cost in fewer outer steps (4 -> 3 and 18 -> 10; message steps 319 -> 307 and 315 -> 219).
TEST(GncJump, OnlyResidualsBeyondTheBoundHoldTheEarlyEndBack) {
  for (const GeneratorResult& dirty :
       {test::flexible_city(0.25, OutlierKind::kRandom, 1), test::grid_with_outliers(0.25)}) {
    const std::vector<int> blocks = test::robots_as_blocks(dirty);
    GncDistributedOptions o = test::irbcd_gnc();
    o.solver.certify = true;
    o.robust.jump_band_max = 0;  // the band of jump_band alone, as above
    o.robust.jump_band_inside = true;
    const GncDistributedResult both = solve_gnc_distributed(dirty.graph, blocks, o);
    o.robust.jump_band_inside = false;
    const GncDistributedResult beyond = solve_gnc_distributed(dirty.graph, blocks, o);
    EXPECT_EQ(both.rejected, dirty.outliers);
    EXPECT_EQ(beyond.rejected, dirty.outliers);
    EXPECT_LT(beyond.outer_iterations, both.outer_iterations);
    EXPECT_NEAR(beyond.final_solve.cost, both.final_solve.cost, 1e-8 * both.final_solve.cost);
    EXPECT_TRUE(beyond.final_solve.certified.value_or(false));
  }
}

// A generated 300-pose city (5 robots on id ranges, the generator's noise and information) with
// 50 % random outliers, seed 4, GNC by the solver's defaults (Newton steps): at the second update
// mu is still small and every loop closure beyond the bound lies beyond 2 c^2, true ones too, so
// the fixed band is empty and GNC ends there with true closures cut that the passes do not all
// take back. With the band widened at mu (up to 30 c^2) those closures still have weight and hold
// the end back: GNC's own set is the labels (nothing taken back), certified.
TEST(GncJump, ClosuresBeyondTheBoundThatStillHaveWeightHoldTheEarlyEndBack) {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kCity;
  g.num_poses = 300;
  g.num_robots = 5;
  g.seed = 4;
  g.outlier_fraction = 0.5;
  const GeneratorResult dirty = generate_pose_graph(g);
  const std::vector<int> blocks = test::robots_as_blocks(dirty);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  // After the plain solve's rounds: weighed at the voted start (RobustOptions::weigh_at_start)
  // the band of B alone does not end GNC early here.
  o.robust.weigh_at_start = false;
  // Ten re-check passes (RobustOptions::readmission_passes' former default): twenty take the
  // cut true closures back after the early end too.
  o.robust.readmission_passes = 10;
  o.robust.jump_band_max = 0;
  const GncDistributedResult fixed = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.jump_band_max = 30;
  const GncDistributedResult at_mu = solve_gnc_distributed(dirty.graph, blocks, o);
  EXPECT_LE(fixed.outer_iterations, 2);
  EXPECT_NE(fixed.rejected, dirty.outliers) << "true closures should stay cut without it";
  EXPECT_GT(at_mu.outer_iterations, fixed.outer_iterations);
  EXPECT_EQ(at_mu.rejected, dirty.outliers);
  EXPECT_EQ(at_mu.readmitted, 0u);
  EXPECT_TRUE(at_mu.final_solve.certified.value_or(false));
}

}  // namespace
}  // namespace tessera
