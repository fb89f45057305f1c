#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/trial_point_watch.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/online/estimate_extension.hpp>
#include <tessera/online/lifted_rank.hpp>
#include <tessera/online/new_pose_placement.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/util/input_error.hpp>

#include "online/trial_points.hpp"

namespace tessera {

DistributedOptions online_solver_options() {
  DistributedOptions o;
  o.local_rounds.enabled = true;
  // The online engine's own settings: Newton steps after new data (online_step_solver), not
  // the batch solve's `--refine auto`.
  o.refine.enabled = false;
  return o;
}

void OnlineOptions::validate() const {
  rebalance.validate();
  if (!(refactor_growth >= 0) || !std::isfinite(refactor_growth))
    throw InputError("OnlineOptions.refactor_growth must be a finite number >= 0");
  if (!(certify_every_s >= 0) || !std::isfinite(certify_every_s))
    throw InputError("OnlineOptions.certify_every_s must be a finite number >= 0 (seconds)");
  if (!(step_every_s >= 0) || !std::isfinite(step_every_s))
    throw InputError("OnlineOptions.step_every_s must be a finite number >= 0 (seconds)");
  if (step_every_s > 0 && real_time)
    throw InputError("OnlineOptions.step_every_s: a fixed step period excludes real_time");
  if (!(newton_forcing > 0 && newton_forcing < 1))
    throw InputError("OnlineOptions.newton_forcing must be in (0, 1)");
  if (newton_coarse_min_blocks < 2)
    throw InputError("OnlineOptions.newton_coarse_min_blocks must be >= 2");
  if (newton_coarse_aggregates < 0)
    throw InputError("OnlineOptions.newton_coarse_aggregates must be >= 0 (0 = auto)");
  if (!(newton_after_grad_tol > 0))
    throw InputError("OnlineOptions.newton_after_grad_tol must be > 0 (+infinity: no round)");
  DistributedOptions s = solver;
  s.certify = certify_at_end;  // the staircase options matter only then
  try {
    s.validate();
  } catch (const InputError& e) {
    throw InputError(std::string("OnlineOptions.solver: ") + e.what());
  }
}

namespace {

using Clock = std::chrono::steady_clock;

double cpu_now() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

}  // namespace

OnlineEngine::OnlineEngine(int d, const OnlineOptions& options)
    : options_(options), stream_(d, "online stream") {
  options_.validate();
  if (options_.solver.rank < d)
    throw InputError("OnlineOptions.solver.rank must be >= d = " + std::to_string(d));
  X_.resize(options_.solver.rank, 0);
}

void OnlineEngine::receive(const StreamBatch& batch) {
  received_.push_back(batch);
}

std::vector<Pose> OnlineEngine::estimate() const {
  if (X_.cols() == 0 || count_components(stream_.graph()) != 1) return {};
  return round_solution(stream_.graph(), X_);
}

double OnlineEngine::step_wall_s() const {
  return std::chrono::duration<double>(Clock::now() - step_wall_start_).count();
}

double OnlineEngine::step_cpu_s() const {
  return cpu_now() - step_cpu_start_;
}

OnlineUpdate OnlineEngine::step(double now_s) {
  step_wall_start_ = Clock::now();
  step_cpu_start_ = cpu_now();
  points_.clear();
  const bool keep = keep_points_;
  OnlineUpdate u;
  u.time_s = now_s;
  double oldest = now_s, newest = 0.0;
  const std::size_t poses_before = stream_.graph().num_poses;
  const std::size_t measurements_before = stream_.graph().measurements.size();
  std::vector<double> stamps;
  for (const StreamBatch& b : received_) {
    u.batches += stream_.absorb(b).batches;
    oldest = std::min(oldest, b.stamp);
    newest = std::max(newest, b.stamp);
    stamps.push_back(b.stamp);
  }
  received_.clear();
  const PoseGraph& graph = stream_.graph();
  u.poses = graph.num_poses - poses_before;
  u.measurements = graph.measurements.size() - measurements_before;
  u.total_poses = graph.num_poses;
  u.total_measurements = graph.measurements.size();
  u.agents = static_cast<int>(stream_.robots().size());
  u.newest_publication_s = stamps.empty() ? now_s : newest;
  // Idle: nothing new and already converged, so no round and no message.
  if ((u.poses == 0 && u.measurements == 0 && converged_) || graph.num_poses == 0) return u;
  step_factors_before_ = blocks_ ? blocks_->tangent_factor_totals() : TangentFactorTotals{};
  const long long built_before = blocks_ ? blocks_->built_total() : 0;

  // New poses join a block (their robot's, or the one holding most of their measurements);
  // then the blocks follow the graph's growth and cut.
  const auto& robots = stream_.robots();
  assign_new_poses(graph, owner_, stream_.robot_blocks_from(owner_.size()), options_.rebalance);
  const RebalanceResult moves =
      rebalance_blocks(graph, owner_, static_cast<int>(robots.size()), options_.rebalance);
  u.moved = moves.moved;
  u.largest_block = moves.largest_after;
  u.smallest_block = moves.smallest_after;
  u.cut = moves.cut_after;
  // Only the measurements since the last extension can touch a new pose.
  std::size_t composed = 0;
  if (u.poses > 0) {
    const std::size_t estimated = static_cast<std::size_t>(X_.cols()) / (graph.d + 1);
    EstimateExtension e = extend_estimate(graph, X_, stream_.guesses(), extended_measurements_);
    X_ = std::move(e.X);
    composed = e.composed;
    if (options_.place_new_poses) place_new_poses(graph, X_, estimated, extended_measurements_);
  }
  extended_measurements_ = graph.measurements.size();
  {
    const ComponentMerges merges = pieces_.absorb(graph, X_, options_.align_merged_pieces);
    u.merges = merges.merges;
    u.merge_poses_moved = merges.poses_moved;
  }
  if (keep) points_.push_back({{"absorbed", step_wall_s(), step_cpu_s(), 0, 0}, X_});
  if (converged_ && composed == u.measurements) {
    // Every new measurement placed a new pose (odometry, mostly): each has zero residual at
    // the composed poses, so f and its gradient are what they were and the agents, which were
    // converged, have nothing to do. Their blocks take the new data in at the next solve.
    u.grad_norm = last_grad_norm_;
    u.relaxation_cost = last_relaxation_cost_;
    u.stop_reason = "unchanged";
  } else {
    DistributedResult res = solve_linked(online_step_solver(options_), keep);
    // Newton steps that stopped above the tolerance (a step far from the model's region, e.g.
    // the closures of sphere2500's last rings: 20 trust-region steps left |grad f| at 9) hand
    // over to the rounds from where they stopped: the step ends under the tolerance either way.
    const bool newton_short = !res.refines.empty() && res.grad_norm > options_.solver.grad_norm_tol;
    const std::vector<NewtonRefineResult> refines = res.refines;
    if (newton_short) {
      DistributedResult more = solve_linked(plain_step_solver());
      more.bytes_exchanged += res.bytes_exchanged;
      more.init_s += res.init_s;
      more.solve_cpu_s += res.solve_cpu_s;
      more.critical_path_cpu_s += res.critical_path_cpu_s;
      res = std::move(more);
    }
    // A stalled iterate (RoundProtocol: cost and gradient repeated bit for bit) cannot improve
    // on this problem: iterating again before new data arrives would only burn rounds.
    converged_ = res.grad_norm <= options_.solver.grad_norm_tol || res.stop_reason == "stalled";
    last_grad_norm_ = res.grad_norm;
    last_relaxation_cost_ = res.relaxation_cost;
    u.rounds = res.rounds;
    u.bytes = res.bytes_exchanged;
    u.grad_norm = res.grad_norm;
    u.stop_reason = res.stop_reason;
    u.setup_s = res.init_s;
    u.rounds_cpu_s = res.solve_cpu_s;
    u.critical_path_cpu_s = res.critical_path_cpu_s;
    u.relaxation_cost = res.relaxation_cost;
    for (const NewtonRefineResult& n : refines) {
      u.newton_steps += n.steps;
      u.newton_cg_iterations += n.cg_iterations;
      u.newton_message_steps += n.message_steps();
    }
    // The step ended where the Newton steps stopped (grad_norm), or where the rounds after them
    // did.
    if (!refines.empty() && !newton_short) u.stop_reason = refines.back().stop_reason;
  }
  if (blocks_) {
    const TangentFactorTotals step = blocks_->tangent_factor_totals().since(step_factors_before_);
    u.factorizations = step.factorizations;
    u.factor_flops = step.flops;
    u.blocks_built = blocks_->built_total() - built_before;
  }
  u.ms = 1000.0 * step_wall_s();
  u.cpu_s = step_cpu_s();
  u.latency_s = now_s - oldest + u.ms / 1000.0;
  u.latency_cpu_s = now_s - oldest + u.cpu_s;
  // Out of the step's times: the step ended here.
  if (keep)
    points_.push_back(
        {{"end", u.ms / 1000.0, u.cpu_s, u.newton_steps, u.newton_cg_iterations, u.factorizations},
         X_});
  for (double stamp : stamps) {
    totals_.batch_latency_s.push_back(now_s - stamp + u.ms / 1000.0);
    totals_.batch_latency_cpu_s.push_back(now_s - stamp + u.cpu_s);
  }
  totals_.rounds += u.rounds;
  totals_.repartitions += u.moved > 0 ? 1 : 0;
  totals_.poses_moved += u.moved;
  totals_.bytes += u.bytes;
  totals_.cpu_s += u.cpu_s;
  totals_.updates.push_back(u);
  return u;
}

DistributedOptions OnlineEngine::plain_step_solver() const {
  OnlineOptions rounds = options_;
  rounds.newton_steps = false;
  return online_step_solver(rounds);
}

DistributedOptions online_step_solver(const OnlineOptions& options) {
  DistributedOptions solver = options.solver;
  solver.certify = false;
  solver.round_result = false;  // the graph may not be connected yet
  if (options.newton_steps) {
    solver.refine.enabled = true;
    solver.refine.when = NewtonRefineOptions::When::kAlways;
    solver.refine.grad_norm_tol = options.solver.grad_norm_tol;
    // The step is done only under the tolerance: a small decrease is no reason to stop.
    solver.refine.relative_decrease_tol = 0.0;
    solver.refine.refactor_every_step = false;
    solver.refine.refactor_grown_factors = options.first_step_on_grown_factors;
    solver.refine.forcing = options.newton_forcing;
    solver.refine.coarse = options.newton_coarse;
    solver.refine.coarse_min_blocks = options.newton_coarse_min_blocks;
    if (options.newton_coarse_aggregates == OnlineOptions::kCoarseAggregatesAuto) {
      solver.refine.coarse_aggregates = OnlineOptions::kCoarseAutoMaxPieces;
      solver.refine.coarse_poses_per_aggregate = OnlineOptions::kCoarseAutoPosesPerPiece;
    } else {
      solver.refine.coarse_aggregates = options.newton_coarse_aggregates;
      solver.refine.coarse_poses_per_aggregate = 0;
    }
    // The coarse matrix from the Hessian's data part, as the kept block factors above are:
    // positive semi-definite at any point. A step that starts far from the optimum (a batch of
    // loop closures) made the Galerkin matrix indefinite or nearly singular, and its inverse
    // sent the trust region's steps where the model did not hold (docs/online.md).
    solver.refine.coarse_multipliers = false;
    // Summed every third accepted step, not every one (docs/online.md, "The coarse matrix
    // kept for a few steps": a fifth less CPU on the 5,000-pose grid for 14 % more CG
    // iterations).
    solver.refine.coarse_keep_steps = 3;
    // Nor the trial translations' re-solve (measured on long chains from a cold start).
    solver.refine.translation_iterations = 0;
    // Nor the interface solves (they factor every block at every point; these steps keep
    // their factors across steps).
    solver.refine.interface_max_coordinates = 0;
    solver.grad_norm_tol = std::max(options.newton_after_grad_tol, solver.grad_norm_tol);
  }
  return solver;
}

double live_refactor_growth(const OnlineOptions& options) {
  if (options.first_step_on_grown_factors && options.newton_steps)
    return std::numeric_limits<double>::infinity();
  return options.refactor_growth;
}

void use_online_refine_space(const LiveBlocks& blocks, const DistributedOptions& solver) {
  if (!solver.refine.enabled || solver.refine.coarse != NewtonRefineOptions::Coarse::kSmoothed)
    return;
  // Until some group of linked blocks is as large as the correction's minimum, the steps are
  // block Jacobi's whatever the space (TangentCoarseSpace::linked(): a piece goes with its
  // block), so the space is not built: it costs a pass over the whole graph at every solve.
  const BlockLayout& layout = blocks.layout();
  std::vector<int> group_blocks(static_cast<std::size_t>(layout.num_blocks), 0);
  int largest = 0;
  for (const std::size_t c : connected_components(layout.adjacent))
    largest = std::max(largest, ++group_blocks[c]);
  if (largest < solver.refine.coarse_min_blocks) {
    for (const auto& s : blocks.states())
      if (s) s->use_refine_space(nullptr);
    return;
  }
  const PoseGraph& g = blocks.graph();
  // One space shared by every held state.
  const auto space = std::make_shared<const CoarseSpace>(make_coarse_space(
      g.num_poses, g.measurements, blocks.layout().owner, solver.refine.coarse_space_options()));
  for (const auto& s : blocks.states())
    if (s) s->use_refine_space(space);
}

DistributedResult OnlineEngine::solve_linked(const DistributedOptions& solver,
                                             bool keep_newton_points) {
  DistributedResult res;
  if (!blocks_)
    blocks_ = std::make_unique<LiveBlocks>(stream_.graph().d, solver.block_update,
                                           live_refactor_growth(options_));
  const auto setup_start = Clock::now();
  blocks_->sync(stream_.graph(), owner_, X_);
  const double setup_s = std::chrono::duration<double>(Clock::now() - setup_start).count();
  if (blocks_->graph().num_poses == 0) return res;
  DistributedOptions run = solver;
  use_online_refine_space(*blocks_, run);
  run.round_result = false;  // in the linked graph's ids: the caller rounds X_
  std::optional<TrialPoints> trials;
  if (keep_newton_points && run.refine.enabled)
    trials.emplace(
        blocks_->layout().num_blocks, [this] { return step_wall_s(); },
        [this] { return step_cpu_s(); },
        [this](int b) {
          return blocks_->states()[static_cast<std::size_t>(b)]->tangent_factorizations_total();
        },
        blocks_->tangent_factor_totals().since(step_factors_before_).factorizations);
  res =
      solve_distributed_watching_trials(blocks_->graph(), blocks_->layout(), blocks_->all_states(),
                                        run, trials ? trials->watch() : TrialPointWatch{});
  res.init_s += setup_s;
  if (res.X.rows() == X_.rows()) {
    blocks_->write_back(res.X, X_);
    // The poses outside the linked graph are the same at every trial point.
    if (trials) trials->accepted(res.refines, *blocks_, X_, points_);
  }
  return res;
}

OnlineResult OnlineEngine::finish() {
  if (!received_.empty()) step(received_.back().stamp);
  OnlineResult out = totals_;
  out.graph = stream_.graph();
  out.keys = stream_.key_of_pose();
  if (out.graph.num_poses == 0) return out;
  DistributedOptions solver = options_.solver;
  solver.certify = options_.certify_at_end;
  // Rounding needs one connected graph (its translation solve fixes one gauge); a mission
  // whose robots never met has no common frame to report.
  solver.round_result = count_components(out.graph) == 1;
  const double cpu_start = cpu_now();
  const DistributedResult res = solve_linked(solver);
  out.cpu_s += cpu_now() - cpu_start;
  out.certified = res.certified;
  out.min_eigenvalue = res.min_eigenvalue;
  out.final_rounds = res.rounds;
  out.bytes += res.bytes_exchanged;
  out.grad_norm = res.grad_norm;
  if (res.X.rows() > X_.rows()) {  // the staircase climbed: the result has more rows
    Eigen::MatrixXd wide = Eigen::MatrixXd::Zero(res.X.rows(), X_.cols());
    wide.topRows(X_.rows()) = X_;
    blocks_->write_back(res.X, wide);
    X_ = std::move(wide);
  }
  if (solver.round_result) {
    out.poses = round_solution(out.graph, X_);
    out.cost = evaluate_objective(out.graph, out.poses);
    out.certified = estimate_certified(out.certified, out.cost, res.relaxation_cost);
  }
  return out;
}

std::optional<OnlineCertificate> OnlineEngine::certify(double now_s) {
  if (X_.cols() == 0 || blocks_ == nullptr) return std::nullopt;
  DistributedOptions solver = options_.solver;
  solver.certify = true;
  solver.round_result = false;
  const double cpu_start = cpu_now();
  OnlineCertificate c;
  c.time_s = now_s;
  c.poses = stream_.graph().num_poses;
  c.cost_before = last_relaxation_cost_;
  const DistributedResult res = solve_linked(solver);
  c.certified = res.certified.value_or(false);
  c.min_eigenvalue = res.min_eigenvalue;
  c.cost_after = res.relaxation_cost;
  if (res.X.rows() > X_.rows() && c.certified) {
    // The climb left a critical point that was not optimal and reached a certified optimum at
    // a higher rank: continue from it, brought back to rank r (exact for a rank <= r optimum).
    Eigen::MatrixXd wide = Eigen::MatrixXd::Zero(res.X.rows(), X_.cols());
    wide.topRows(X_.rows()) = X_;
    blocks_->write_back(res.X, wide);
    X_ = project_to_rank(wide, stream_.graph().d, static_cast<int>(X_.rows()));
    c.escaped = true;
    converged_ = false;  // the next step solves from the projected point
  } else if (res.X.rows() == X_.rows()) {
    last_relaxation_cost_ = res.relaxation_cost;
    last_grad_norm_ = res.grad_norm;
  }
  c.cpu_s = cpu_now() - cpu_start;
  totals_.cpu_s += c.cpu_s;
  totals_.bytes += res.bytes_exchanged;
  totals_.certificates.push_back(c);
  return c;
}

OnlineResult run_online(int d, const std::vector<StreamBatch>& batches,
                        const OnlineOptions& options, const OnlineObserver& observer,
                        const OnlineStepStart& before_step) {
  OnlineEngine engine(d, options);
  double clock = 0.0, next_certificate = options.certify_every_s;
  std::size_t next = 0;
  while (next < batches.size()) {
    // Without real time, each distinct stamp is one step; with it, everything published
    // while the previous step ran enters together.
    if (options.step_every_s > 0)  // the first period that holds the next batch
      clock =
          std::max(clock + options.step_every_s,
                   std::ceil(batches[next].stamp / options.step_every_s) * options.step_every_s);
    else
      clock = std::max(clock, batches[next].stamp);
    const std::size_t first = next;
    while (next < batches.size() && batches[next].stamp <= clock) engine.receive(batches[next++]);
    if (before_step) before_step(engine, next - first);
    const OnlineUpdate u = engine.step(clock);
    if (observer && (u.poses > 0 || u.measurements > 0 || u.rounds > 0)) observer(engine, u);
    if (options.real_time) clock += u.ms / 1000.0;
    if (options.certify_every_s > 0 && clock >= next_certificate &&
        engine.certify(clock).has_value())
      next_certificate = clock + options.certify_every_s;
  }
  return engine.finish();
}

}  // namespace tessera
