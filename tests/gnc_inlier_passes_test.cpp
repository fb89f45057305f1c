// The inlier passes' bookkeeping of the distributed GNC (robust/gnc_inlier_passes.hpp, no
// solve): which pass is capped, when an unchanged verdict stands, the passes' budget.

#include "robust/gnc_inlier_passes.hpp"

#include <gtest/gtest.h>

#include <tessera/robust/robust_options.hpp>

namespace tessera {
namespace {

// A pass solved to the tolerance, ended, then a capped one opened from it.
void capped_pass_after_solved_one(GncInlierPasses& passes) {
  passes.solve_next_fully();
  passes.open(false);
  passes.solved();
  passes.open(false);
}

TEST(GncInlierPasses, APassIsCappedUnlessItRefinesOrASolvedPassWasAsked) {
  const RobustOptions o;
  GncInlierPasses passes(o);
  passes.open(false);
  EXPECT_TRUE(passes.capped());
  passes.open(true);  // hands over to the refinement: solved to the tolerance
  EXPECT_FALSE(passes.capped());
  passes.solve_next_fully();
  passes.open(false);
  EXPECT_FALSE(passes.capped());
  passes.open(false);  // the request held for one pass only
  EXPECT_TRUE(passes.capped());
}

TEST(GncInlierPasses, NoPassIsCappedWithoutARoundCap) {
  RobustOptions o;
  o.recheck_max_rounds = 0;
  GncInlierPasses passes(o);
  passes.open(false);
  EXPECT_FALSE(passes.capped());
  EXPECT_FALSE(passes.unchanged_needs_full_pass(false));
}

TEST(GncInlierPasses, AnUnchangedVerdictFromASolvedPassStandsWhenAFinalSolveFollows) {
  const RobustOptions o;
  GncInlierPasses passes(o);
  capped_pass_after_solved_one(passes);
  ASSERT_TRUE(passes.capped());
  EXPECT_FALSE(passes.unchanged_needs_full_pass(true));
  EXPECT_TRUE(passes.unchanged_needs_full_pass(false));  // the last pass is the answer
}

TEST(GncInlierPasses, AnUnchangedVerdictOnACappedPassNeedsASolvedOneWithoutConfirmation) {
  RobustOptions o;
  o.recheck_confirm_solved = false;
  GncInlierPasses passes(o);
  capped_pass_after_solved_one(passes);
  EXPECT_TRUE(passes.unchanged_needs_full_pass(true));
}

TEST(GncInlierPasses, APassAfterAFreshStartVoteDoesNotStartFromASolvedPass) {
  const RobustOptions o;
  GncInlierPasses passes(o);
  passes.solve_next_fully();
  passes.open(false);
  passes.solved();
  passes.forget_solved_start();
  passes.open(false);
  EXPECT_TRUE(passes.unchanged_needs_full_pass(true));
}

TEST(GncInlierPasses, TheBudgetCountsJudgedPassesUntilItRestarts) {
  RobustOptions o;
  o.readmission_passes = 2;
  GncInlierPasses passes(o);
  passes.judged();
  EXPECT_FALSE(passes.budget_spent());
  passes.judged();
  EXPECT_TRUE(passes.budget_spent());
  passes.restart_budget();
  EXPECT_FALSE(passes.budget_spent());
  passes.last_full_pass();  // one more pass, solved, and no verdict opens another
  EXPECT_TRUE(passes.budget_spent());
  passes.open(false);
  EXPECT_FALSE(passes.capped());
}

}  // namespace
}  // namespace tessera
