#pragma once
// Options of the robust (outlier-rejecting) solve: `--robust`, `--inlier-threshold`,
// `--inlier-quantile`, `--gnc-max-outer`, `--gnc-mu-step`, `--known-inliers` (docs/robust.md).

#include <string>

namespace tessera {

/// The robust scheme. kNone solves plain least squares (every measurement weight 1).
enum class RobustKind {
  kNone,
  /// Graduated non-convexity with a truncated-least-squares cost (Yang, Antonante, Tzoumas,
  /// Carlone 2020): an outer loop over mu, each step a warm-started weighted solve followed
  /// by the closed-form TLS weight update.
  kGncTls,
  /// Pairwise consistency maximisation first (pairwise_consistency.hpp): closures outside the
  /// largest mutually consistent set start GNC-TLS with weight 0. Centralized only.
  kPcmGnc,
};

/// Which measurements are never down-weighted.
enum class KnownInliers {
  kOdometry,  ///< Measurements between consecutive pose ids (|i - j| = 1): odometry.
  kNone,      ///< Every measurement may be rejected.
};

/// When a distributed re-check probe may cut kept measurements (its tail side) while the
/// rejected set is still GNC's own, untouched by the re-check passes (RobustOptions::probe_cut).
enum class ProbeCut {
  kAlways,       ///< Whatever the set.
  kAfterPasses,  ///< Only once the passes (or a kept probe) changed GNC's set.
  /// After the passes where every weighted solve of GNC was a Newton step
  /// (RobustOptions::gnc_refine_steps), always where GNC's solves were rounds.
  kAuto,
};

/// Which weight changes at an update hold the adaptive mu step back to RobustOptions::mu_step
/// (RobustOptions::mu_step_hold).
enum class MuStepHold {
  kCrossings,  ///< Any weight that crossed 1/2, either way.
  kFalls,      ///< Only a weight that fell below 1/2: a measurement left the inlier set.
};

const char* robust_kind_name(RobustKind kind);              ///< "none", "gnc-tls" or "pcm-gnc".
RobustKind parse_robust_kind(const std::string& name);      ///< InputError lists valid names.
const char* known_inliers_name(KnownInliers known);         ///< "odometry" or "none".
KnownInliers parse_known_inliers(const std::string& name);  ///< InputError lists valid names.
const char* probe_cut_name(ProbeCut cut);                   ///< "always", "after-passes" or "auto".
ProbeCut parse_probe_cut(const std::string& name);          ///< InputError lists valid names.
const char* mu_step_hold_name(MuStepHold hold);             ///< "crossings" or "falls".
MuStepHold parse_mu_step_hold(const std::string& name);     ///< InputError lists valid names.

struct RobustOptions {
  RobustKind kind = RobustKind::kNone;
  /// Bound c on a measurement's whitened residual r (r^2 = kappa ||R_j - R_i R_ij||_F^2 +
  /// tau ||t_j - t_i - R_i t_ij||^2, the measurement's term of the objective): TLS charges
  /// min(r^2, c^2). 0 (default) means c^2 = a quantile of the chi-square distribution with
  /// d(d+1)/2 degrees of freedom (3 in 2D, 6 in 3D), which is r^2's law for a measurement
  /// whose noise matches its information (inlier_quantile says which). > 0 otherwise.
  double inlier_threshold = 0.0;
  /// Probability of that quantile, in (0, 1); 0 (default) means 1 - 1e-4 / m for m
  /// measurements that may be rejected: the chance that *any* true measurement lies beyond
  /// the bound at the truth is then about 1e-4 whatever the graph's size (a union bound).
  /// Why so far out: GNC-TLS starts every edge with r^2 > c^2 / sqrt(2) below full weight and
  /// can push such an edge out, and real files have true edges with r^2 near 27 at their
  /// optimum (cubicle, 16,869 edges: 26.3; manhattan3500_sesync: 26.3), which 1 - 0.01 / m
  /// (cubicle: c^2 = 37.7; sesync manhattan: 4 edges lost) or a fixed 0.9999 (c^2 = 27.9,
  /// cubicle lost 3) do not clear. Outliers of any use lie orders of magnitude further out.
  double inlier_quantile = 0.0;
  /// Most outer GNC steps (weighted solves after the first plain one), >= 1.
  int max_outer_iterations = 100;
  /// mu grows by this factor each outer step, > 1. 1.4 is the paper's value.
  double mu_step = 1.4;
  /// Adaptive mu schedule, distributed solvers only: after a weight update that moved no
  /// measurement across weight 1/2 (summed over the agents: the inlier set is unchanged) the
  /// next step is the last one squared, up to this factor; any change returns it to mu_step.
  /// 0 (default) = off, every step mu_step; otherwise >= mu_step.
  double mu_step_max = 0.0;
  /// Distributed solvers only: the mu_step_max that applies, while mu_step_max is 0, where every
  /// weighted solve of GNC so far was a Newton step (gnc_refine_steps, where the team's interface
  /// fits; decided from each solve's layout, the same on every agent); 0 = none (mu_step there
  /// too), else > 1 (a value below mu_step caps nothing). `tessera solve
  /// --gnc-newton-mu-step-max`. Why: a Newton step ends each weighted solve near its minimiser,
  /// as the centralized GNC's full solves do, so a bigger step of mu while no weight crosses 1/2
  /// moves only weights that stay on their side. 4: F = 0.25 random, 5 agents, message steps
  /// 168 -> 159 on intel (15 -> 14 outer steps), 0.5 159 -> 109 (14 -> 8), intel group 0.25 466 ->
  /// 412, CSAIL 0.5 72 -> 63, group 0.5 213 -> 204; every intel and CSAIL cell of the benchmark
  /// (random and group 0.1 / 0.25 / 0.5) the same answer; 2 and 9 give the same answers (9 the
  /// same counts, 2 intel 0.5 127). Where GNC's solves are rounds nothing changes (there adaptive
  /// mu cost manhattan3500 a probe: docs/robust.md, "Fewer outer steps").
  double newton_mu_step_max = 4.0;
  /// Distributed solvers only, with the adaptive step (mu_step_max, newton_mu_step_max): which
  /// weight changes at an update return the next step to mu_step. kFalls (default): only
  /// weights that fell below 1/2 (a measurement left the inlier set); kCrossings: a weight that
  /// crossed 1/2 either way. Why: at a fixed iterate a larger mu only raises weights across 1/2
  /// (the weight 1/2 lies at r^2 = c^2 mu (mu + 1) / (mu + 1/2)^2, which grows with mu), so
  /// rises are the schedule's own doing and say nothing about whether the inlier set is
  /// settling; a fall comes from the iterate moving a residual out. On intel with 25 % random
  /// outliers 4-63 weights crossed 1/2 at 12 of the 13 updates after the first and none fell,
  /// so with kCrossings the bigger step ran once. `tessera solve --gnc-mu-hold falls|crossings`.
  /// F = 0.25 random, 5 agents, crossings -> falls: intel 14 -> 7 outer steps, 121 -> 76 message
  /// steps; intel random 0.1 / 0.5 119 -> 70 / 90 -> 82, group 0.1 / 0.25 the same sets, group 0.5
  /// precision 0.885 -> 0.879, recall 0.781 -> 0.797; CSAIL every cell the same set, random 0.1
  /// 81 -> 106 (docs/robust.md, "Only falling weights hold the bigger step back").
  MuStepHold mu_step_hold = MuStepHold::kFalls;
  /// Distributed solvers only: GNC ends early when, at a weight update, no measurement that may
  /// be rejected has its r^2 within a factor of this of the bound (c^2 / B < r^2 < B c^2, summed
  /// over the agents with the weight votes): each weight then jumps to TLS's own verdict at that
  /// iterate (1 within the bound, 0 beyond it; both ends map the same transmitted weight the same
  /// way, core/robust/gnc_votes.hpp, tls_verdict_weight) and the rejected set goes straight to
  /// the inlier passes, which re-check it at the kept set's solution. > 1, or 0 = off. Why: mu
  /// grows by 1.4 a step until every weight is binary, while the residuals often separate from
  /// the bound steps earlier, and the steps after that only move weights whose verdict is
  /// already clear (CSAIL with 25 % random outliers, 5 agents: from outer step 11 of 18 exactly
  /// the 32 wrong closures lie beyond c^2 and none within [c^2/2, 2 c^2]). 2: the band of mu = 1.
  /// F = 0.25 random, with --gnc-pass-refine auto --gnc-mu-step-max 4: CSAIL 18 -> 11 outer
  /// steps, 218 -> 138 message steps; intel 19 -> 14, 349 -> 283; the same exact sets. Where a
  /// residual stays near the bound to the end nothing changes (intel 0.5, manhattan3500,
  /// sphere2500, the 1000-pose grid: the same outer steps and answers).
  double jump_band = 2.0;
  /// Distributed solvers only, with jump_band: whether residuals within the bound also hold the
  /// early end back (true: the band (c^2 / B, B c^2), both sides; `tessera solve --gnc-jump-side
  /// both`) or only those beyond it, (c^2, B c^2) (false, default). Why one side can do: at the
  /// end each weight takes TLS's own verdict, and the passes then solve the kept set with every
  /// kept measurement at weight 1 and cut the kept ones beyond the bound at that solution, so a
  /// residual just within the bound is judged there on the kept set itself; a rejected one is
  /// out of those solves, and one just beyond the bound can stay there at the kept set's solution
  /// (a true closure whose cut lets the map relax), which is what GNC's graduated weights are
  /// for. intel with 25 % random outliers, 5 agents: from outer step 14 of 18 every wrong closure
  /// lies beyond 43 c^2 and no residual in (c^2, 2 c^2), while a true closure's r^2 falls from
  /// 0.95 c^2 to 0.41 c^2 over steps 14-17. F = 0.25 random, one side against both: intel 251 ->
  /// 224 message steps, the 1000-pose grid 384 -> 304, sphere2500 728 -> 706, CSAIL and
  /// manhattan3500 the same, every set and cost the same; the cells that lose are manhattan3500
  /// random 0.5, 10,399 -> 10,469 message steps (+0.7 %, the same set) and group 0.5, 91,347 ->
  /// 93,115 (+1.9 %, the same set, not certified either way) (docs/robust.md, "Early end").
  bool jump_band_inside = false;
  /// Distributed solvers only, with jump_band: at small mu the band widens to where the weights
  /// at the update's mu reach 0, (c^2, min((mu + 1) / mu, M) c^2) with M this value, and never
  /// below jump_band (within the bound, with jump_band_inside, the mirror image): a closure beyond
  /// the bound that still has weight holds the early end back. <= jump_band (e.g. 0): the band
  /// stays (c^2, B c^2) whatever mu; for mu >= 1 / (B - 1) (mu >= 1 at B = 2) it is that band
  /// anyway. Why: mu starts at c^2 / (2 max r^2 - c^2), so early in the schedule every loop
  /// closure is graduated, and on a map still bent by the wrong closures every one of them, true or
  /// wrong, can lie beyond 2 c^2: the fixed band is then empty, and GNC ended at the first or
  /// second update at TLS's verdict at a plain solve's iterate. Generated graphs with 50 % random
  /// outliers (`tessera generate --robots 5 --outliers 0.5`, 5 agents) lost 6, 28 and 2 true
  /// closures that the inlier passes never took back (grid3d 300 poses seeds 1 and 3, city 300
  /// seed 4); with M = 30 all 48 files of grid3d / city, 125 / 300 poses, F = 0.25 / 0.5,
  /// seeds 1-6 end exact. Why a cap: at small mu a weight falls like c / r, and the random wrong
  /// closures of CSAIL seed 2 keep some r^2 within 100 c^2 for steps (M = 100 or no cap: 0.25
  /// from 51 to 69 message steps, the same set); M = 10 leaves the 125-pose city seed 3 at 0.5
  /// with 16 true closures cut (docs/robust.md, "Early end").
  double jump_band_max = 30.0;
  /// Distributed solvers only, with recheck_probes: whether a probe may cut kept measurements
  /// (its tail side) while the rejected set is still GNC's own, untouched by the re-check passes
  /// (kAlways), only once the passes or a kept probe changed it (kAfterPasses: before that it
  /// only brings back the return band), or (kAuto, default) after the passes where every
  /// weighted solve of GNC was a Newton step and always where GNC's solves were rounds (decided
  /// from each solve's layout, gnc_solve_setup.hpp: the same on every agent). Why: where GNC
  /// runs on Newton steps (intel and CSAIL at 5 agents) it ends on near-minimisers of each
  /// weighted problem, and every tail cut from its own set on the benchmark's cells was refused
  /// (intel random 0.1/0.25/0.5, every CSAIL cell: the cut true closures come back; ~56 message
  /// steps each on intel, 20 on CSAIL), while where GNC's solves are 5 rounds the cut undoes a
  /// fold: manhattan3500 with 25 % group outliers needs it (with it 12,265 message steps,
  /// precision 0.974, recall 0.980, certified; without, 76,603, 0.899, 0.949, not certified).
  /// F = 0.25 random, 5 agents, always -> auto: intel 224 -> 168 message steps, CSAIL 92 -> 72,
  /// every other graph the same run; every answer the same on the benchmark's cells run
  /// (docs/robust.md, "Cut only after the passes changed GNC's set").
  /// `tessera solve --gnc-probe-cut always|after-passes|auto`.
  ProbeCut probe_cut = ProbeCut::kAuto;
  /// Distributed solvers only: most rounds of every solve before the final one (the first,
  /// unweighted solve and each weighted solve between two weight updates), >= 0, 0 = no cap.
  /// GNC needs only a rough minimiser between weight updates (dpgo's robust mode also updates
  /// weights after a fixed number of iterations); measurements misjudged on a rough iterate
  /// are re-admitted after the final solve of the inlier set, which runs to the tolerance.
  /// 5: on the 1000-pose grid with 25 % random outliers, 152 rounds in all (3.9x the clean run)
  /// with the same rejected set as full inner solves (2388 rounds) (docs/robust.md, "Rounds").
  int inner_max_rounds = 5;
  /// Centralized solver only: most trust-region iterations of every solve before the re-check
  /// passes (the first, unweighted solve and each weighted solve between two weight updates),
  /// >= 0, 0 = no cap (default). The centralized counterpart of inner_max_rounds. Off by
  /// default because it costs quality where GNC needs real minimisers: manhattan3500 with 25 %
  /// random outliers keeps 1 wrong closure and cuts 4 true ones uncapped (certified), 3 and 7
  /// with a cap of 3, 1 and 10 with 5 (not certified), for 2.5x / 1.1x fewer CG iterations. What
  /// made large contaminated files slow was the factorization, not the iterations
  /// (CentralizedOptions::supernodal_min_flops; docs/benchmarks/robust.md).
  int inner_max_iterations = 0;
  KnownInliers known_inliers = KnownInliers::kOdometry;
  /// Re-check passes after GNC: at the inlier set's solution each measurement that may be
  /// rejected gets TLS's own verdict: a rejected one within the bound (r^2 <= c^2) was misjudged
  /// on an earlier iterate and comes back, a kept one beyond it (a wrong closure GNC's iterate
  /// fitted with the help of a distortion) leaves; the new set is solved again, at most this many
  /// times, >= 0 (0 = never). Each pass lowers the TLS cost or ends the passes. 20: manhattan3500
  /// with 25 % random outliers needs 4 (docs/robust.md, "Re-check"); robust.py's sphere2500 with
  /// 75 % group outliers, distributed, needs more than 10: at 10 the budget ran out while the
  /// passes still changed the set, so no probe could follow and 6 wrong closures stayed (precision
  /// 0.925, not certified, 22,405 message steps); at 20 exact and certified in 3,486.
  int readmission_passes = 20;
  /// Distributed solvers only: most rounds of a re-check pass's solve while the set may still
  /// change, >= 0, 0 = no cap. The passes end only after a pass solved to the tolerance changed
  /// nothing. 20: sphere2500 with 25 % random outliers, 5 agents: 255 rounds in all against 530
  /// with every pass to the tolerance (the clean run: 67), the same rejected set.
  int recheck_max_rounds = 20;
  /// Distributed solvers only: a capped pass that changes nothing also ends the passes when it
  /// started from a pass solved to the tolerance (the set then differs from a solved one only
  /// by that pass's few flips, and 20 rounds from its solution settle them); without this a
  /// further pass to the tolerance confirms it. The final solve (or the judgement of a probe)
  /// follows either way. Off: every end of the passes is a verdict at a pass solved to the
  /// tolerance. true: manhattan3500 with 25 % random outliers, 5 agents: 5,275 rounds in all
  /// against 7,104 (the clean run: 1,228), the same rejected set, cost and certificate
  /// (docs/robust.md, "Distributed").
  bool recheck_confirm_solved = true;
  /// Most probes after the re-check passes, >= 0 (0 = none); the centralized solve's tail
  /// probes take the same budget, probe_ratio and probe_tail_ratio (docs/robust.md, "Tail
  /// probes, centralized"). Distributed, when a
  /// pass solved to the tolerance changes nothing, each agent proposes the kept measurements it
  /// weighs whose residual is within the bound but above probe_ratio times the median residual
  /// of those measurements; all of them leave, the passes run again (putting back what fits),
  /// and the result stays only when its TLS cost (summed over the agents) is lower than before
  /// the probe; otherwise the set and iterate from before the probe are restored. Why: a few
  /// wrong closures can bend the map until each of them fits within the bound, so no
  /// one-at-a-time verdict cuts them, while cutting them together lowers the TLS cost
  /// (manhattan3500 with 25 % random outliers: 6 wrong closures kept at r^2 1.4-12 against a
  /// median of 0.05 and c^2 = 37; docs/robust.md, "Probes").
  int recheck_probes = 2;
  /// The probe's bound over the median residual of the kept measurements an agent weighs, > 1.
  /// 5: manhattan3500 with 25 % random outliers ends exact with 5 (20 and 10 leave one wrong
  /// closure in: its residual at the rank-r iterate is below those multiples). On a file whose
  /// noise matches its information (median r^2 about 2.4 in 2D, 5.3 in 3D, c^2 37-48) probes
  /// may run and are undone when the TLS cost does not fall: they cost rounds, not accuracy.
  double probe_ratio = 5.0;
  /// An agent proposes probes only when the mean residual of the kept measurements it weighs is
  /// above this times their median, >= 0 (0 = always). Residuals that match their information
  /// have a mean near the median (chi-square: 1.27x in 2D, 1.12x in 3D); a bent map has a heavy
  /// tail. 1.5: sphere2500 with 25 % random outliers, whose agents have 1.2-1.33, ran a probe
  /// that could not lower the TLS cost (65 rounds: 371, 5.5x the clean run, instead of 306), while
  /// manhattan3500's agents have 1.64-5.5 and keep their probe (docs/robust.md, "Probes").
  double probe_tail_ratio = 1.5;
  /// A probe also brings back the rejected measurements whose r^2 at the kept set's solution is
  /// above the bound but within this times c^2, >= 1 (1 = none); with the cut ones, when there
  /// are any, and judged by the same TLS cost. Why: a true closure that is the only tie of two
  /// stretches of the map lets them relax once it is gone, so at the kept set's solution it lies
  /// just beyond the bound and no one-at-a-time verdict takes it back, while with it the TLS cost
  /// is lower (torus3D with 25 % random outliers: closure 4973-73 at r^2 = 48.6 against c^2 =
  /// 46.9 there, 5.6 at the clean optimum, TLS cost 24,227 with it against 24,257 without).
  /// Random wrong closures lie far beyond (there: the nearest at 12.7 c^2). Centralized, the
  /// same band is the return probes' (gnc_centralized.hpp): all of it together, then, with
  /// cluster probes, one closure at a time (tls_recheck.hpp, return_candidates).
  double probe_return_ratio = 4.0;
  /// Centralized solver only: most swap probes after the other probes, >= 0 (0 = none). A swap
  /// cuts a kept closure whose r^2 is at least swap_kept_ratio x c^2 and brings back a rejected
  /// one within swap_return_ratio x c^2 with an end within swap_near pose ids of one of its
  /// ends (most strained kept closure first), runs the re-check passes from there and stays only
  /// when the TLS cost over every measurement falls (core/robust/swap_probe.hpp). Why: a wrong
  /// closure can bend the map around one of its ends until it fits, and the true closure that
  /// meets it there is cut; each alone is judged right at that bent solution, and a return
  /// probe cannot undo it while the wrong one holds the bend (sphere2500 with 50 % random
  /// outliers: wrong closure 5626 (1696-2406) kept at r^2 39.2 against c^2 = 46.2, true closure
  /// 4195 (1696-1746) cut at 2.9 c^2, cost over the kept set 1,984.7 against f*_clean 1,687.0;
  /// docs/robust.md, "Swap probes"). 3: there the true closure 4145 at r^2 43.8, which also meets
  /// pose 1696, comes first. A strained kept closure with no such rejected one is cut alone when
  /// its r^2 is also above probe_ratio x the median r^2 of the kept closures (a wrong closure
  /// bent to fit where no true closure was cut: sphere2500 75 %, wrong closure 6144 (429-2009) at
  /// r^2 18.1 against a median of 0.27, c^2 = 46.5); the pairs come first.
  int swap_probes = 3;
  /// A swap's two closures have an end within this many pose ids, >= 0. 0: the fold's wrong and
  /// true closure share a pose.
  int swap_near = 0;
  /// The kept closure of a swap has r^2 >= this x c^2, in [0, 1]. 0.25: a closure bent to fit
  /// sits near the bound (39.2 / 46.2 above), the true closures of a file whose noise matches
  /// its information have a median r^2 near 0.1 c^2 (5.3 in 3D, 2.4 in 2D against c^2 37-48).
  double swap_kept_ratio = 0.25;
  /// The rejected closure of a swap has r^2 <= this x c^2, >= 1. 10: the fold's true closure
  /// lies at 2.9 c^2, the nearest of the 1,225 random wrong closures at 27 c^2.
  double swap_return_ratio = 10.0;
  /// Distributed solvers only: the final solve of the kept set (weights fixed) ends with the
  /// distributed Newton refinement (distributed/newton_refine.hpp, with the solver's
  /// DistributedOptions::refine settings: ||grad f|| <= 1e-6 by default), whatever
  /// DistributedOptions::refine.enabled says for the other solves; with it that solve runs even
  /// without certification. Why: the block-coordinate rounds stop at the solver's gradient
  /// tolerance, which leaves the cost a few 1e-6 above the optimum of the kept set
  /// (manhattan3500, 25 % random outliers: 8e-6 relative), while the refinement reaches it to
  /// rounding error in fewer rounds than the block updates would need (docs/robust.md, "Final
  /// solve").
  bool final_refine = true;
  /// Distributed solvers only, with `--refine auto` (the solver's NewtonRefineOptions::when =
  /// kIfRoundsSlow): an inlier pass solved to the tolerance hands over to the Newton refinement
  /// where the team's interface fits its interface solves, as a clean solve does, and GNC's
  /// weighted solves there are Newton steps too (gnc_refine_steps); capped passes, the first
  /// solve and graphs whose interface does not fit are solved by rounds alone. On (default,
  /// `--gnc-pass-refine auto`); off: every solve before the final one by rounds alone. Why: where
  /// the clean run is mostly refinement (intel, CSAIL at 5 agents: 1 and 0 rounds, 15 and 13
  /// message steps) the robust run's rounds are what costs (F = 0.25 random: intel 1,033 message
  /// steps off, 195 on; CSAIL 965 and 66; the same exact sets, certified). Where the interface
  /// does not fit (manhattan3500, sphere2500, city10000, the 1000-pose grid at 5 agents) nothing
  /// changes: there the refinement's block-Jacobi CG would cost more message steps than the
  /// rounds it saves (16 rounds for 1,958 message steps), hence the limit (docs/robust.md,
  /// "Final solve").
  bool refine_passes = true;
  /// Distributed solvers only, with refine_passes: where the team's interface fits the
  /// refinement's interface solves (the test of refine_passes, on each weighted solve's layout),
  /// each weighted solve of GNC (every one after the first, plain solve) is this many Newton
  /// steps of the refinement (distributed/newton_refine.hpp) from the previous iterate instead of
  /// inner_max_rounds rounds; and an inlier pass that hands over to the refinement does so at
  /// once, without block-coordinate rounds first. >= 0; 0 = GNC's weighted solves by rounds (and
  /// the passes' rounds run down to the hand-over gradient first, as a clean solve's do). The first
  /// solve stays rounds: from the start, a Newton step goes to the plain problem's nearest
  /// minimiser, which the wrong closures have bent (intel with 50 % random outliers: 88 true
  /// closures cut, not certified). Why: one Newton step of a weighted problem costs 7 message
  /// steps (one CG iteration of the interface solve: 2 neighbour exchanges, 5 all-agent sums)
  /// and takes its gradient from ~170 to ~0.05, while 5 rounds (10 message steps) leave it rough;
  /// GNC on near-minimisers misjudges fewer closures, so the passes after it change less
  /// (F = 0.25 random, 5 agents, with mu_step_max 4: intel 283 -> 188 message steps, CSAIL 138 ->
  /// 66; docs/robust.md, "Newton steps in GNC"). 1: two steps cost 13 message steps a solve and
  /// shorten nothing (intel 0.25: 17 outer steps either way, 284 message steps; CSAIL 87).
  int gnc_refine_steps = 1;
  /// Distributed solvers only, where GNC's weighted solves are Newton steps (gnc_refine_steps):
  /// the weights are updated at a Newton step's point only when its quadratic model held there:
  /// the step was accepted and lowered f by at least this fraction of the model's predicted
  /// decrease (the trust region's usual "very successful" test; a step cut short on the trust
  /// region's boundary or at negative curvature passes it when its model held). Otherwise the
  /// iterate goes back to the step's start and the same weighted problem is solved by
  /// rounds (inner_max_rounds), and the weights are updated there. Every agent decides the same
  /// (the verdicts are on summed values; no message). [0, 1]; 0 = off (every Newton step's end
  /// is taken as the weighted solve's answer). Why: GNC follows the weighted problem's
  /// minimiser as mu grows, and far from one (after a rough first solve) the Newton model does
  /// not hold: on intel with robust.py's seed-2 random outliers every step at 25 % was rejected,
  /// so GNC sharpened its weights around the first solve's point (|grad f| 4e4) and cut ~200
  /// true closures, and at 10 % an accepted step with ratio 0.32 led into a fold; the passes
  /// then left 3 / 2 / 2 true closures cut at 0.1 / 0.25 / 0.5 (docs/robust.md, "Newton steps in
  /// GNC"). With the test those cells are exact.
  double newton_step_trust = 0.75;
  /// Distributed solvers only, where GNC's weighted solves are Newton steps (gnc_refine_steps):
  /// in those steps every agent factors the interface solves' Sigma itself
  /// (NewtonRefineOptions::SigmaFactoring::kEveryAgent) where the solver's refinement would have
  /// agent 0 alone factor it and send each agent its part of every solve (kShipSolves, the
  /// default where Sigma has at least ship_solves_min_coordinates coordinates); other
  /// factorings, the passes and the final solve keep the solver's. The same iterates either way.
  /// On, a weighted solve (one point, one CG direction) saves the message step of waiting for
  /// agent 0's solve; the price is every agent receiving every share and factoring Sigma.
  /// Off by default because that price is larger than the step it saves: F = 0.25 random, 5
  /// agents, on against off: intel 149 against 156 message steps, 29.8 against 18.8 MB, 3.53
  /// against 2.55 G instructions over all agents (+38 %; in process, callgrind, with the factors'
  /// analyses kept across the weighted solves, NewtonRefineOptions::analyses); CSAIL 71 against
  /// 73; every intel and CSAIL cell of the benchmark the same `--out` bytes and rejected set
  /// (docs/robust.md, "Who factors Sigma in GNC's Newton steps").
  /// `tessera solve --gnc-step-sigma every|refine-sigma`.
  bool step_sigma_every_agent = false;
  /// Distributed solvers only: GNC's exchanges ride on messages that are sent anyway, with the
  /// same values, so the run is the same but for its message steps (and bytes):
  /// - where a weighted solve is a single Newton step (gnc_refine_steps 1) that another weight
  ///   update follows, each agent sends its neighbours the trial point's public poses beside the
  ///   trial's sums; accepted, that point is the iterate whose poses the weight update needs, so
  ///   the pose exchange after the solve waits for nothing (not accepted, the iterate is the
  ///   solve's start, whose poses every agent holds from the exchange before);
  /// - every weights message also carries the sender's other measurements of weight below 1/2,
  ///   so GNC's rejected set (the weights do not change after the last weight exchange) needs
  ///   no exchange of its own;
  /// - with the kept set's fresh start (GncAgentInput::kept_set_start), the agents send agent 0
  ///   the values of the measurements they weigh once, beside the first weights, so a fresh
  ///   start waits only for agent 0's answer; that answer also carries each agent's neighbours'
  ///   poses of the start, so where the iterate has not moved since the last pose exchange
  ///   (after GNC's early end, or a pass's verdict) the two starts' pose exchange is left out.
  /// On (default); off: every one of those exchanges. Why: each is a wait for peers like a
  /// round. F = 0.25 random, 5 agents: intel 166 -> 150 message steps, CSAIL 74 -> 67; every
  /// intel and CSAIL cell of the benchmark the same `--out` bytes and rejected set
  /// (docs/robust.md, "Exchanges that ride along").
  bool exchanges_ride_along = true;
  /// Distributed solvers only: the solves of the kept set (the inlier passes and the final
  /// solve) start at their Newton refinement where their rounds would only open with a pose
  /// exchange whose poses every agent holds and stop at their first status. An inlier pass that
  /// hands over to the refinement at once (refine_passes, gnc_refine_steps) starts so after the
  /// previous pass's pose exchange, or at the kept set's fresh start, whose neighbour poses came
  /// with it; the final solve where it starts at the last pass's point, after that pass's pose
  /// exchange, and that pass's summed gradient on the same set is within half the rounds'
  /// tolerance. The refinement and the certificate run as before. On (default); off: those solves
  /// open with their rounds. Why: two message steps a solve (F = 0.25 random, 5 agents: intel
  /// 140 -> 136, CSAIL 67 -> 63), the same `--out` bytes, rejected set and certificate
  /// (docs/robust.md, "The kept set's solves start at their refinement").
  bool kept_solves_start_at_refinement = true;
  /// Distributed solvers only, with exchanges_ride_along: where a weighted solve is a single
  /// Newton step that another weight update follows, each agent computes that update at the
  /// trial point (its neighbours' poses there are known once the trial's translations are
  /// solved) and sends its weights message beside the trial's sums; accepted, the trial point is
  /// the iterate, so the weight exchange after the solve waits for nothing (not accepted, the
  /// exchange runs as before). A cut measurement of weight 0 whose other end the weighted solve
  /// does not hold (it left the solve's layout) has no known pose at the trial point: it stays
  /// at weight 0 and out of the early end's count until the inlier passes judge it at the kept
  /// set's solution. On (default); off: the weight exchange of its own. Why: one message step
  /// an outer step (F = 0.25 random, 5 agents: 13 fewer on intel, 4 on CSAIL; 122 and 58 at the
  /// defaults), every intel and CSAIL cell of the benchmark the same `--out` bytes and rejected
  /// set (docs/robust.md, "Weights beside the trial's sums").
  bool weights_ride_trial_sums = true;
  /// Distributed solvers only, with the start vote (GncAgentInput::Y0_known): its exchange of
  /// both starts' public poses is also the first solve's opening pose exchange. Every agent
  /// holds its neighbours' poses of the start the vote takes, so the first solve's rounds begin
  /// at their round-0 status with them (CertifiedAgent::start_with_neighbours), the same
  /// iterates. On (default); off: the first solve opens with its own pose exchange. Why: one
  /// message step a run (F = 0.25 random, 5 agents: intel 123 -> 122, CSAIL 59 -> 58); every
  /// intel and CSAIL cell of the benchmark the same `--out` bytes and rejected set
  /// (docs/robust.md, "The first solve takes the start vote's poses").
  bool first_solve_takes_start_poses = true;
  /// Distributed solvers only, with the start vote (GncAgentInput::Y0_known), where GNC's
  /// weighted solves are Newton steps (gnc_refines, gnc_solve_setup.hpp): GNC's first weights
  /// (and mu's start) are taken at the start the vote takes, with no plain solve before them. The
  /// start is the cheaper in TLS cost of the solver's initialization and the known inliers' own
  /// (the odometry chain); a few rounds of the plain problem from there only bend it toward every
  /// closure, wrong ones included, and leave it far from any minimiser (intel with 25 % random
  /// outliers: |grad f| ~4e4 after 5 rounds), where the first weighted Newton step's model need not
  /// hold (negative curvature on robust.py's seed-2 intel 0.25 file; the weights are then solved by
  /// rounds first, newton_step_trust). On (default); off: the first solve runs inner_max_rounds
  /// rounds of the plain problem first. Why: intel random 0.1 / 0.25 / 0.5, 5 agents, robust.py's
  /// seeds 1 and 2: 95 / 75 / 81 and 79 / 97 / 101 -> 62 / 69 / 64 and 65 / 69 / 70 message steps,
  /// every set exact and certified. Not by rounds: manhattan3500 with 25 % random outliers then
  /// kept a wrong closure (docs/robust.md, "GNC weighs at the voted start").
  bool weigh_at_start = true;
  /// Distributed solvers only: an inlier pass that runs Newton steps sends each trial point's
  /// public poses to the neighbours beside the trial's sums (tagged with the trial's number);
  /// the pose exchange after the pass then reads those of the last accepted trial, which is the
  /// pass's point to the bit, instead of waiting for an exchange of its own. Without an accepted
  /// trial the exchange runs as before. On (default); off: the exchange of its own. Why: one
  /// message step per refined pass (F = 0.25 random, 5 agents: intel 122 -> 121, CSAIL
  /// 58 -> 57), the same `--out` bytes and rejected sets (docs/robust.md, "A pass's poses beside
  /// its trials' sums").
  bool pass_poses_ride_trial_sums = true;
  /// Distributed solvers only, with exchanges_ride_along and the kept set's fresh start: when GNC
  /// ends early (jump_band) at a weight update, the vote between the iterate and the kept set's
  /// fresh start that follows needs no exchange of its own. Each agent's weights message carries
  /// its cost over the measurements it weighs that TLS's verdict at that update keeps (the cost
  /// the vote would sum at the iterate), and agent 0, which computes the fresh start from every
  /// measurement's value, sends the start's cost over the kept set beside each agent's block
  /// (summed per weight owner in file order, then in agent-id order: the vote's own sums, to the
  /// bit). Every agent then compares the same two sums. Other votes (after a probe, before the
  /// final solve, after GNC ended without the early end) run their exchange as before. On
  /// (default); off: the vote's exchange. Why: one message step a run with outliers, the same
  /// iterates (intel random 0.25, 5 agents: 76 -> 75; docs/robust.md, "The fresh start's vote
  /// beside the weights").
  bool kept_vote_rides_weights = true;
  /// Stop when sum_e w_e (1 - w_e) falls below this (weights binary), >= 0.
  double weight_tolerance = 1e-6;

  /// Throws InputError naming the first field out of range (e.g. "RobustOptions.mu_step").
  void validate() const;
};

}  // namespace tessera
