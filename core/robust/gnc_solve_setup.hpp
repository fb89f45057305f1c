#pragma once
// What each solve of the distributed GNC runs with (GncAgent decides which solve runs when):
// its solver options, and the measurements of GNC's own solves at their weights.

#include <cstdint>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/measurement.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <vector>

namespace tessera {

/// The solver options of one solve, from the run's:
/// - GNC's solves (the first and the weighted ones) need only a rough minimiser: uncertified,
///   at most RobustOptions::inner_max_rounds rounds (0: no cap);
/// - an inlier pass is uncertified; one whose set may still change (`pass_capped`) needs only a
///   rough solution too and stops after RobustOptions::recheck_max_rounds (the verdict that
///   ends the passes is taken at a converged one);
/// - the final solve certifies as the run asks, and with RobustOptions::final_refine ends with
///   the Newton refinement (the answer to the refinement's tolerance).
/// `newton_steps` (GNC's weighted solves, where gnc_refines()): the solve is
/// RobustOptions::gnc_refine_steps Newton steps of the refinement, handed over at once.
DistributedOptions gnc_solve_options(const GncDistributedOptions& options, GncSolveKind kind,
                                     bool pass_capped, bool newton_steps = false);

/// Whether an inlier pass on `layout` (the kept set's) hands over to the Newton refinement
/// (RobustOptions::refine_passes under `--refine auto`, where the team's interface fits the
/// refinement's interface solves: the rule of CertifiedAgent's early hand-over, from the layout
/// alone, so every agent decides the same). Such a pass is solved to the tolerance whether or not
/// its set may still change: the refinement from the previous pass's iterate costs fewer message
/// steps than RobustOptions::recheck_max_rounds rounds (intel with 25 % random outliers, 5
/// agents: 7-13 against 40 a pass).
bool pass_refines(const GncDistributedOptions& options, const BlockLayout& layout, int d);

/// Whether GNC's weighted solve on `layout` (that step's: without the cut measurements of weight
/// 0) is RobustOptions::gnc_refine_steps Newton steps instead of rounds: with refine_passes, where
/// the interface fits as for pass_refines(). From the layout alone, so every agent decides the
/// same.
bool gnc_refines(const GncDistributedOptions& options, const BlockLayout& layout, int d);

/// The measurements of GNC's solve: each at its weight (`weighted`; the first solve is plain).
/// A weight of exactly 0 adds nothing: with `drop_zero` (the known inliers keep the poses
/// connected) such a measurement leaves the solve (fewer block neighbours, fewer colours);
/// otherwise it stays at a tiny pull so no part is cut off.
std::vector<Measurement> gnc_solve_measurements(const std::vector<Measurement>& measurements,
                                                const std::vector<double>& weights, bool weighted,
                                                bool drop_zero);

/// The measurements of `measurements` (file positions `index`, ascending) not in `rejected`
/// (ascending), and their file positions: what the inlier passes and the final solve work on.
void gnc_kept_measurements(const std::vector<Measurement>& measurements,
                           const std::vector<std::uint64_t>& index,
                           const std::vector<std::uint64_t>& rejected,
                           std::vector<Measurement>& kept, std::vector<std::uint64_t>& kept_index);

}  // namespace tessera
