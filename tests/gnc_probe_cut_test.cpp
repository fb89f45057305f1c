// When a distributed re-check probe may cut kept measurements (RobustOptions::probe_cut_untouched).
#include <gtest/gtest.h>

#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <vector>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

using test::grid_with_outliers;
using test::irbcd_gnc;
using test::robots_as_blocks;

// The 125-pose grid with 25 % random outliers: GNC rejects exactly the wrong closures and the
// passes change nothing. With probe_ratio 1.5 and no tail rule the agents name half the true
// closures for a probe. Run from GNC's own set (probe_cut_untouched, the default) the probe cuts
// them, the passes take them back and the TLS cost refuses it; with probe_cut_untouched false a
// probe cuts only after the passes changed the set, so no probe runs: the same set and cost in
// fewer rounds.
TEST(GncProbeCut, NoProbeCutsKeptMeasurementsWhileTheSetIsStillGncsOwn) {
  const GeneratorResult dirty = grid_with_outliers(0.25);
  const std::vector<int> blocks = robots_as_blocks(dirty);
  GncDistributedOptions o = irbcd_gnc();
  o.solver.certify = true;
  o.robust.probe_ratio = 1.5;
  o.robust.probe_tail_ratio = 0;
  o.robust.probe_cut_untouched = false;
  const GncDistributedResult after_passes = solve_gnc_distributed(dirty.graph, blocks, o);
  o.robust.probe_cut_untouched = true;
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

}  // namespace
}  // namespace tessera
