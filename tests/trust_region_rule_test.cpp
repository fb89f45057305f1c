// The Newton refinement's trust-region rule (distributed/trust_region_rule.hpp): a trial is
// taken when f fell by enough of what the model predicted, the radius follows the ratio, and
// a model that rose takes no trial, whatever f did.

#include "distributed/trust_region_rule.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace tessera {
namespace {

TEST(TrustRegionRule, AStepThatLowersFAsPredictedIsTakenAndABoundaryStepDoublesTheRadius) {
  const TrustRegionVerdict v = judge_trust_region_step(100.0, 99.0, 1.0, 2.0, 2.0, true, 0.05);
  EXPECT_TRUE(v.accepted);
  EXPECT_NEAR(v.rho, 1.0, 1e-9);
  EXPECT_EQ(v.radius, 4.0);
}

TEST(TrustRegionRule, AStepThatRaisesFIsRejectedAndTheRadiusIsAQuarterOfTheStep) {
  const TrustRegionVerdict v = judge_trust_region_step(100.0, 100.5, 1.0, 2.0, 0.0, false, 0.05);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.radius, 0.5);
}

// Two increases make a positive ratio: f rose by 235 where the model rose by 184 (a step
// whose gauge part was taken off after its CG, gauge_space.hpp) must not be taken.
TEST(TrustRegionRule, AModelThatRisesTakesNoTrialEvenWhenFRoseInProportion) {
  const TrustRegionVerdict v = judge_trust_region_step(91.6, 326.9, -183.5, 10.0, 0.0, false, 0.05);
  EXPECT_GT(v.rho, 0.05);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.radius, 2.5);
}

TEST(TrustRegionRule, AtRoundOffBothDecreasesAreRegularised) {
  // f = 1e3, decreases of 1e-14 and -1e-14: the regularisation (1e3 eps |f|) dominates.
  const TrustRegionVerdict v =
      judge_trust_region_step(1e3, 1e3 + 1e-14, 1e-14, 1e-6, 0.0, false, 0.05);
  EXPECT_TRUE(v.accepted);
  EXPECT_GT(v.rho, 0.75);
}

TEST(TrustRegionRule, ANonFiniteTrialCostIsRejected) {
  const TrustRegionVerdict v = judge_trust_region_step(
      1.0, std::numeric_limits<double>::quiet_NaN(), 0.5, 1.0, 0.0, false, 0.05);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.radius, 0.25);
}

}  // namespace
}  // namespace tessera
