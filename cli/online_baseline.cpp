#include "online_baseline.hpp"

#include <algorithm>
#include <ctime>
#include <tessera/graph/connectivity.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera::cli {

namespace {

double cpu_now() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

// Blocks numbered 0..k-1 in order of first use (a prefix may miss a later robot's block).
std::vector<int> compact(std::vector<int> assignment) {
  std::vector<int> label;
  for (int& b : assignment) {
    auto it = std::find(label.begin(), label.end(), b);
    if (it == label.end()) it = label.insert(label.end(), b);
    b = static_cast<int>(it - label.begin());
  }
  return assignment;
}

// A pose no measurement touches would leave its block without a problem.
bool every_pose_linked(const PoseGraph& g) {
  std::vector<char> linked(g.num_poses, 0);
  for (const Measurement& m : g.measurements) linked[m.i] = linked[m.j] = 1;
  return std::find(linked.begin(), linked.end(), 0) == linked.end();
}

}  // namespace

[[gnu::noinline]] DistributedResult resolve_from_scratch(const PoseGraph& g,
                                                         const std::vector<int>& assignment,
                                                         const OnlineOptions& options, bool newton,
                                                         const std::vector<Pose>& initial) {
  OnlineOptions o = options;
  o.newton_steps = newton;
  DistributedOptions scratch = newton ? online_step_solver(o) : o.solver;
  scratch.certify = false;
  scratch.round_result = false;          // the graph may not be connected yet
  scratch.local_rounds.enabled = false;  // a solve from scratch: every block has work
  DistributedResult r = solve_distributed(g, assignment, scratch, initial);
  if (newton && r.grad_norm > options.solver.grad_norm_tol) {
    DistributedOptions rounds = o.solver;
    rounds.certify = false;
    rounds.round_result = false;
    rounds.local_rounds.enabled = false;
    const std::vector<NewtonRefineResult> refines = r.refines;
    DistributedResult more = solve_distributed_from_lifted(g, assignment, rounds, r.X);
    more.refines = refines;
    r = std::move(more);
  }
  return r;
}

OnlineBaseline::OnlineBaseline(const Arguments& a, const ReplayPlan& plan, int d,
                               const OnlineOptions& options)
    : plan_(plan), options_(options), lag_(d, "baseline stream") {
  enabled_ = a.has("baseline");
  per_ = a.get_or("baseline-per", "publication");
  if (per_ != "publication" && per_ != "closure" && per_ != "step")
    throw InputError("option --baseline-per: '" + per_ +
                     "' is not one of publication, closure, step");
  init_ = a.get_or("baseline-init", "chordal");
  if (init_ != "guesses" && init_ != "chordal")
    throw InputError("option --baseline-init: '" + init_ + "' is not one of guesses, chordal");
  solver_ = a.get_or("baseline-solver", "newton");
  if (solver_ != "rounds" && solver_ != "newton")
    throw InputError("option --baseline-solver: '" + solver_ + "' is not one of rounds, newton");
  every_ = a.get_long("baseline-every", 1);
  if (every_ < 1) throw InputError("option --baseline-every: must be >= 1");
  const long samples = a.get_long("baseline-samples", 0);
  if (samples < 0) throw InputError("option --baseline-samples: must be >= 0");
  std::size_t closures = 0, publications = 0;
  for (const StreamBatch& b : plan.batches) {
    std::size_t k = 0;
    for (const StreamMeasurement& m : b.measurements)
      k += m.kind != MeasurementKind::kOdometry ? 1 : 0;
    closures += k;
    publications += k > 0 ? 1 : 0;
  }
  counted_ = static_cast<long>(per_ == "closure" ? closures : publications);
  if (samples > 0)  // per step: at most one per publication, so K may be smaller
    every_ = std::max<long>(1, counted_ / samples);
}

void OnlineBaseline::resolve(const PoseGraph& g, const std::vector<int>& assignment,
                             const std::vector<Pose>& guesses) {
  // Chordal initialization needs one connected graph; pieces that have not met yet start from
  // the guesses.
  const bool chordal = init_ == "chordal" && count_components(g) == 1;
  chordal_ += chordal ? 1 : 0;
  if (before_resolve) before_resolve(g.num_poses, g.measurements.size());
  const double c0 = cpu_now();
  const DistributedResult r = resolve_from_scratch(g, assignment, options_, solver_ == "newton",
                                                   chordal ? std::vector<Pose>{} : guesses);
  cpu_s_ += cpu_now() - c0;
  rounds_ += r.rounds;
  for (const NewtonRefineResult& n : r.refines) cg_ += n.cg_iterations;
}

bool OnlineBaseline::every_pose_linked_up_to(std::size_t count) {
  const PoseGraph& lg = lag_.graph();
  unlinked_ += lg.num_poses - linked_.size();
  linked_.resize(lg.num_poses, 0);
  for (; linked_measurements_ < count; ++linked_measurements_) {
    const Measurement& m = lg.measurements[linked_measurements_];
    for (const std::size_t p : {m.i, m.j}) {
      unlinked_ -= linked_[p] ? 0 : 1;
      linked_[p] = 1;
    }
  }
  return unlinked_ == 0;
}

void OnlineBaseline::consider(const OnlineEngine& engine, std::size_t count) {
  // Called once per publication (or closure) of the replay: the graph is copied only for the
  // sampled ones (a copy per publication made the 50,000-pose grid's baseline quadratic).
  if (!every_pose_linked_up_to(count)) {
    ++skipped_;
    return;
  }
  // Sampled in the middle of every stride of every_.
  if (solves_++ % every_ != every_ / 2) return;
  ++sampled_;
  const PoseGraph& lg = lag_.graph();
  PoseGraph prefix;
  prefix.d = lg.d;
  prefix.num_poses = lg.num_poses;
  prefix.measurements.assign(lg.measurements.begin(),
                             lg.measurements.begin() + static_cast<std::ptrdiff_t>(count));
  std::vector<int> assignment(
      engine.assignment().begin(),
      engine.assignment().begin() + static_cast<std::ptrdiff_t>(prefix.num_poses));
  resolve(prefix, compact(std::move(assignment)), lag_.guesses());
}

void OnlineBaseline::observe(const OnlineEngine& engine, const OnlineUpdate& u) {
  if (!enabled_) return;
  const PoseGraph& g = engine.stream().graph();
  const auto& kinds = engine.stream().kinds();
  const bool closure =
      std::any_of(kinds.end() - static_cast<std::ptrdiff_t>(u.measurements), kinds.end(),
                  [](MeasurementKind k) { return k != MeasurementKind::kOdometry; });
  closure_steps_ += closure ? 1 : 0;
  if (per_ == "step" && closure) {
    if (!every_pose_linked(g)) {
      ++skipped_;
    } else if (solves_++ % every_ == 0) {  // sampled: the others not re-solved
      ++sampled_;
      resolve(g, engine.assignment(), engine.stream().guesses());
    }
  }
  // The lagging stream takes the step's batches one at a time (same order, so the same ids as
  // the engine's stream).
  while ((lag_.graph().num_poses < g.num_poses ||
          lag_.graph().measurements.size() < g.measurements.size()) &&
         lag_next_ < plan_.batches.size()) {
    const StreamGrowth grown = lag_.absorb(plan_.batches[lag_next_++]);
    std::size_t in_batch = 0;
    for (std::size_t k = grown.first_new_measurement;
         k < grown.first_new_measurement + grown.num_new_measurements; ++k) {
      if (lag_.kinds()[k] == MeasurementKind::kOdometry) continue;
      ++closures_;
      ++in_batch;
      if (per_ == "closure") consider(engine, k + 1);
    }
    publications_ += in_batch > 0 ? 1 : 0;
    if (per_ == "publication" && in_batch > 0) consider(engine, lag_.graph().measurements.size());
  }
}

void OnlineBaseline::add_to(JsonObject& j) const {
  if (!enabled_) return;
  j.add("baseline_per", per_)
      .add("baseline_init", init_)
      .add("baseline_solver", solver_)
      .add("baseline_every", static_cast<int>(every_))
      .add("baseline_closures", closures_)
      .add("baseline_publications", publications_)
      .add("baseline_skipped", skipped_)
      .add("baseline_closure_steps", closure_steps_)
      .add("baseline_chordal_starts", chordal_)
      .add("baseline_measured_rounds", rounds_)
      .add("baseline_measured_cg_iterations", cg_)
      .add("baseline_solves", solves_)
      .add("baseline_resolved", sampled_)
      .add("baseline_measured_cpu_s", cpu_s_)
      .add("baseline_cpu_s", sampled_ > 0 ? cpu_s_ * solves_ / sampled_ : 0.0);
}

}  // namespace tessera::cli
