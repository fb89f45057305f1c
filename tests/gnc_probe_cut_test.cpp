// When a distributed re-check probe may cut kept measurements (RobustOptions::probe_cut).
#include <gtest/gtest.h>

#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "gnc_fixtures.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

using test::grid_with_outliers;
using test::irbcd_gnc;
using test::robots_as_blocks;

// The 125-pose grid with 25 % random outliers: GNC rejects exactly the wrong closures and the
// passes change nothing. With probe_ratio 1.5 and no tail rule the agents name half the true
// closures for a probe. Run from GNC's own set (ProbeCut::kAlways) the probe cuts them, the
// passes take them back and the TLS cost refuses it; with kAfterPasses a probe cuts only after the
// passes changed the set, so no probe runs: the same set and cost in fewer rounds.
TEST(GncProbeCut, NoProbeCutsKeptMeasurementsWhileTheSetIsStillGncsOwn) {
  const GeneratorResult dirty = grid_with_outliers(0.25);
  const std::vector<int> blocks = robots_as_blocks(dirty);
  GncDistributedOptions o = irbcd_gnc();
  o.solver.certify = true;
  o.robust.probe_ratio = 1.5;
  o.robust.probe_tail_ratio = 0;
  o.robust.probe_cut = ProbeCut::kAfterPasses;
  const GncDistributedResult after_passes = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.probe_cut = ProbeCut::kAlways;
  const GncDistributedResult always = solve_gnc_distributed(dirty.graph, blocks, o);

  ASSERT_EQ(always.probes, 1);
  EXPECT_EQ(always.probes_kept, 0);
  EXPECT_EQ(always.readmitted + always.late_rejected, 0u) << "the passes left GNC's set alone";
  EXPECT_EQ(after_passes.probes, 0);
  EXPECT_EQ(after_passes.rejected, dirty.outliers);
  EXPECT_EQ(always.rejected, dirty.outliers);
  EXPECT_LT(after_passes.total_rounds, always.total_rounds);
  EXPECT_NEAR(after_passes.final_solve.cost, always.final_solve.cost,
              1e-8 * always.final_solve.cost);
  EXPECT_TRUE(after_passes.final_solve.certified.value_or(false));
}

// ProbeCut::kAuto (the default): the same 125-pose grid, now with GNC's weighted solves and the
// passes by Newton steps (refine_passes, gnc_refine_steps 1: the interface fits). GNC's own set
// is then taken on near-minimisers and the forced probe's cut side waits for the passes to change
// it: no probe, the same set and cost as with kAlways in fewer message steps. With GNC's solves
// by rounds (gnc_refine_steps 0) kAuto cuts from GNC's own set, as kAlways does.
TEST(GncProbeCut, AutoCutsFromGncsOwnSetOnlyWhereGncsSolvesWereRounds) {
  const GeneratorResult dirty = grid_with_outliers(0.25);
  const std::vector<int> blocks = robots_as_blocks(dirty);
  GncDistributedOptions o;  // the solver's defaults: --refine auto
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.probe_ratio = 1.5;
  o.robust.probe_tail_ratio = 0;
  ASSERT_EQ(o.robust.probe_cut, ProbeCut::kAuto);
  const GncDistributedResult newton_auto = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.probe_cut = ProbeCut::kAlways;
  const GncDistributedResult newton_always = solve_gnc_distributed(dirty.graph, blocks, o);

  ASSERT_GT(newton_always.refine_message_steps, 0) << "GNC's solves should be Newton steps here";
  ASSERT_EQ(newton_always.probes, 1);
  EXPECT_EQ(newton_always.probes_kept, 0);
  EXPECT_EQ(newton_auto.probes, 0);
  EXPECT_EQ(newton_auto.rejected, dirty.outliers);
  EXPECT_EQ(newton_always.rejected, dirty.outliers);
  EXPECT_NEAR(newton_auto.final_solve.cost, newton_always.final_solve.cost,
              1e-8 * newton_always.final_solve.cost);
  EXPECT_TRUE(newton_auto.final_solve.certified.value_or(false));
  EXPECT_LT(message_steps(newton_auto), message_steps(newton_always));

  o.robust.gnc_refine_steps = 0;  // GNC's weighted solves by rounds
  o.robust.probe_cut = ProbeCut::kAuto;
  const GncDistributedResult rounds_auto = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.probe_cut = ProbeCut::kAlways;
  const GncDistributedResult rounds_always = solve_gnc_distributed(dirty.graph, blocks, o);
  EXPECT_EQ(rounds_auto.probes, rounds_always.probes);
  EXPECT_GE(rounds_auto.probes, 1);
  EXPECT_EQ(rounds_auto.rejected, rounds_always.rejected);
  EXPECT_EQ(message_steps(rounds_auto), message_steps(rounds_always));
  EXPECT_EQ(rounds_auto.final_solve.cost, rounds_always.final_solve.cost);
}

TEST(GncProbeCut, NamesAndABadValueNameTheField) {
  for (ProbeCut c : {ProbeCut::kAlways, ProbeCut::kAfterPasses, ProbeCut::kAuto})
    EXPECT_EQ(parse_probe_cut(probe_cut_name(c)), c);
  EXPECT_THROW(parse_probe_cut("sometimes"), InputError);
  RobustOptions o;
  o.probe_cut = static_cast<ProbeCut>(7);
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.probe_cut"));
}

}  // namespace
}  // namespace tessera
