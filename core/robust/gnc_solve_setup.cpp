#include "robust/gnc_solve_setup.hpp"

#include <algorithm>
#include <limits>
#include <tessera/robust/weighted_graph.hpp>

#include "distributed/interface_solve.hpp"

namespace tessera {

DistributedOptions gnc_solve_options(const GncDistributedOptions& options, GncSolveKind kind,
                                     bool pass_capped, bool newton_steps) {
  DistributedOptions o = options.solver;
  // `--refine auto` (the default) is about the accuracy of the answer: GNC's own solves and the
  // inlier passes are intermediate iterates whose accuracy the schedule sets, so only an
  // explicit `--refine newton` refines them, or RobustOptions::refine_passes the passes solved to
  // the tolerance, and then only where the interface fits: the rounds' own gap estimate never
  // asks for the refinement there.
  const bool auto_refine = o.refine.when == NewtonRefineOptions::When::kIfRoundsSlow;
  switch (kind) {
    case GncSolveKind::kGnc:
      o.certify = false;
      if (options.robust.inner_max_rounds > 0)
        o.max_rounds = std::min(o.max_rounds, options.robust.inner_max_rounds);
      if (auto_refine) o.refine.enabled = false;
      if (auto_refine && newton_steps) {
        // RobustOptions::gnc_refine_steps: the rounds hand over at once (their tolerance is the
        // hand-over gradient), and the refinement stops after that many steps.
        o.refine.enabled = true;
        o.refine.auto_interface_grad_tol = std::numeric_limits<double>::infinity();
        o.refine.max_steps = options.robust.gnc_refine_steps;
        // RobustOptions::step_sigma_every_agent: one direction per point does not pay for
        // agent 0's solves' message step.
        if (options.robust.step_sigma_every_agent &&
            o.refine.sigma_factoring == NewtonRefineOptions::SigmaFactoring::kShipSolves)
          o.refine.sigma_factoring = NewtonRefineOptions::SigmaFactoring::kEveryAgent;
        // A weighted solve is one Newton step, one trial: agent 0's translation solve would
        // add a message step to each, for a small factor (the trial translations' Sigma, one
        // row per interface pose) that every agent factors in about the time it waits.
        o.refine.translation_one_factor_min_poses = std::numeric_limits<int>::max();
      }
      break;
    case GncSolveKind::kInlierPass:
      o.certify = false;
      if (pass_capped) o.max_rounds = std::min(o.max_rounds, options.robust.recheck_max_rounds);
      if (auto_refine && (pass_capped || !options.robust.refine_passes)) o.refine.enabled = false;
      if (auto_refine) o.refine.auto_gap_tol = std::numeric_limits<double>::infinity();
      // A refined pass starts near the previous solution: Newton steps from there at once (no
      // rounds down to the hand-over gradient first; intel 25 % random: 236 -> 188 message steps).
      if (auto_refine && o.refine.enabled && options.robust.gnc_refine_steps > 0)
        o.refine.auto_interface_grad_tol = std::numeric_limits<double>::infinity();
      break;
    case GncSolveKind::kFinal:
      if (options.robust.final_refine) {
        o.refine.enabled = true;
        o.refine.when = NewtonRefineOptions::When::kAlways;
      } else if (auto_refine) {
        // Switched off means the rounds' answer: `auto` would otherwise refine wherever the
        // team's interface fits the interface solves.
        o.refine.enabled = false;
      }
      break;
  }
  return o;
}

bool pass_refines(const GncDistributedOptions& options, const BlockLayout& layout, int d) {
  if (!options.robust.refine_passes) return false;
  const NewtonRefineOptions& r =
      gnc_solve_options(options, GncSolveKind::kInlierPass, false).refine;
  return interface_fits(r, layout, d);
}

bool gnc_refines(const GncDistributedOptions& options, const BlockLayout& layout, int d) {
  return options.robust.gnc_refine_steps > 0 && options.robust.refine_passes &&
         interface_fits(gnc_solve_options(options, GncSolveKind::kGnc, false, true).refine, layout,
                        d);
}

std::vector<Measurement> gnc_solve_measurements(const std::vector<Measurement>& measurements,
                                                const std::vector<double>& weights, bool weighted,
                                                bool drop_zero) {
  std::vector<Measurement> out;
  out.reserve(measurements.size());
  for (std::size_t k = 0; k < measurements.size(); ++k) {
    if (drop_zero && weights[k] == 0) continue;
    // Not one push_back of a conditional: with a const lvalue on one side its result is a
    // const prvalue, which push_back copies instead of moving.
    if (weighted)
      out.push_back(weighted_measurement(measurements[k], weights[k]));
    else
      out.push_back(measurements[k]);
  }
  return out;
}

void gnc_kept_measurements(const std::vector<Measurement>& measurements,
                           const std::vector<std::uint64_t>& index,
                           const std::vector<std::uint64_t>& rejected,
                           std::vector<Measurement>& kept, std::vector<std::uint64_t>& kept_index) {
  kept.clear();
  kept_index.clear();
  for (std::size_t k = 0; k < measurements.size(); ++k)
    if (!std::binary_search(rejected.begin(), rejected.end(), index[k])) {
      kept.push_back(measurements[k]);
      kept_index.push_back(index[k]);
    }
}

}  // namespace tessera
