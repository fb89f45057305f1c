#include "solve_online.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/online/step_points.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "json_writer.hpp"
#include "online_baseline.hpp"
#include "online_options_json.hpp"
#include "rebalance_args.hpp"
#include "robot_files.hpp"
#include "run_wide_args.hpp"
#include "runtime/replay_input.hpp"
#include "solve_distributed.hpp"
#include "step_coarse_args.hpp"

namespace tessera::cli {

const char* const kOnlineValued[] = {
    "rate",          "speedup",           "start",          "checkpoints",
    "certify-every", "refactor-growth",   "baseline-every", "local-threshold",
    "step-every",    "step-solver",       "newton-after",   "threads",
    "baseline-per",  "baseline-samples",  "baseline-init",  "baseline-solver",
    "until",         "progress-interval", "gap-bound",      "first-step-factors",
    nullptr};
const char* const kOnlineSwitches[] = {"online",          "real-time",   "baseline",
                                       "no-local-rounds", "no-progress", nullptr};

const char* kOnlineHelp =
    "\n"
    "Online (--online; docs/online.md): the graph arrives as the robots' front ends would\n"
    "publish it (`tessera replay`'s timeline) while one agent per robot solves in this\n"
    "process; every new batch is absorbed at a round boundary and solved from the current\n"
    "estimate until ||grad f|| <= --grad-tol again. GRAPH: a g2o file or robot files.\n"
    "  --algorithm rbcd|rbcd++|irbcd, --grad-tol T, --max-rounds K, --rank R   as above\n"
    "  --robots R                robots sharing a whole g2o file (default 1)\n"
    "  --rate R                  poses per second per robot (default 10)\n"
    "  --speedup S               time divisor of the replay (default 1)\n"
    "  --start S0,S1,...         seconds at which each robot starts (default all 0)\n"
    "  --real-time               a step absorbs all batches published while the previous one\n"
    "                            ran (its wall time counts as stream time); default: one step\n"
    "                            per publication time\n"
    "  --step-every S            a step every S seconds of stream time (absorbing all that\n"
    "                            was published by then), whatever the machine's load\n"
    "                            (>= 0; default 0 = off: --real-time or one step per\n"
    "                            publication time)\n"
    "  --checkpoints K           at K evenly spaced steps, the estimate's relative gap to the\n"
    "                            optimum of the graph received so far (centralized solver,\n"
    "                            computed after the run, not timed; default 0 = none), and\n"
    "                            how soon after its last data the estimate came within\n"
    "                            --gap-bound of it\n"
    "  --gap-bound B             the checkpoints' relative gap bound (default 1e-3, > 0)\n"
    "  --baseline                also re-solve from scratch (no warm start) after every loop\n"
    "                            closure, to the same tolerance, and report its CPU time\n"
    "  --baseline-per publication|closure|step   publication (default): once per batch a\n"
    "                            front end published with closures in it, on the graph up to\n"
    "                            and with it; closure: once per closure measurement, on the\n"
    "                            graph up to and with it; step: once per step that brought a\n"
    "                            closure, on the graph at the end of the step\n"
    "  --baseline-init chordal|guesses   the re-solves' start: the batch solver's chordal\n"
    "                            initialization (default; the front ends' guesses while the\n"
    "                            graph is not connected) or the front ends' guesses\n"
    "  --baseline-solver newton|rounds   the re-solves' solver: the online steps' Newton\n"
    "                            steps from scratch (default: the cheaper on the generated\n"
    "                            graphs) or the batch solver's rounds\n"
    "  --baseline-every K        re-solve only every K-th of them and scale the CPU time by\n"
    "                            (counted / re-solved): an estimate for graphs where re-solving\n"
    "                            after every closure would take hours (default 1)\n"
    "  --baseline-samples M      the same with K chosen for about M re-solves spread evenly\n"
    "                            over the replay (default 0: use --baseline-every)\n"
    "  --certify-every S         also certify every S seconds of stream time (default 0: at\n"
    "                            the end only)\n"
    "  --refactor-growth G       a growing block keeps its preconditioner factor, the new\n"
    "                            poses appended to it, until it has G times more poses than\n"
    "                            it was computed for (default 0: a new factor whenever the\n"
    "                            block gets new poses)\n"
    "  --first-step-factors new|grown   newton: the preconditioner of a step's first Newton\n"
    "                            step, the grown blocks' new factors (default) or their held\n"
    "                            factors with the new poses appended, new ones built at the\n"
    "                            first accepted Newton step's point (no factorization\n"
    "                            before that point, but appending costs more on large\n"
    "                            3-D blocks; docs/online.md)\n"
    "  --threads T               the agents handle their messages on T threads (1..64,\n"
    "                            default 1); the same iterates as one thread\n"
    "  --tangent-dots split|sequential   the block factors' backward dot products as four\n"
    "                            partial sums (default) or CHOLMOD's sequential sums\n"
    "  --local-threshold F       local rounds: a block works only while its gradient norm\n"
    "                            is above F * grad-tol / sqrt(blocks), in (0, 1] (default 1)\n"
    "  --no-local-rounds         every block works and sends in every round\n"
    "  --step-solver newton|rounds   how a step gets the gradient back under --grad-tol:\n"
    "                            distributed Newton steps from the warm start (default) or\n"
    "                            block-coordinate rounds only\n"
    "  --newton-after T          newton: rounds first, down to ||grad f|| <= T (default: none)\n"
    "  --until S                 play only what is published up to S seconds of stream time\n"
    "                            (a prefix of the mission, e.g. to profile its steps; the\n"
    "                            final cost needs the graph received by then connected;\n"
    "                            default: the whole mission)\n"
    "  --no-certify              skip the final certificate\n"
    "  --json FILE               summary with the `updates` array (one object per step); a\n"
    "                            long run rewrites it at every progress line with the steps\n"
    "                            so far and \"complete\": false\n"
    "  --progress-interval S     a progress line on stderr (step, stream time, poses, CPU,\n"
    "                            re-solves) at most every S seconds of wall time, and one per\n"
    "                            phase after the steps (default 10; 0: after every step)\n"
    "  --no-progress             no progress lines\n";

namespace {

// Linear interpolation between the nearest ranks. Some values may be +infinity (checkpoints
// never within the gap bound): where no interpolation is needed, the value itself, not inf - inf.
double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  if (frac == 0.0 || v[lo] == v[hi]) return v[lo];
  return v[lo] + frac * (v[hi] - v[lo]);
}

JsonObject update_json(const OnlineUpdate& u) {
  JsonObject j;
  j.add("time_s", u.time_s)
      .add("batches", u.batches)
      .add("poses", u.poses)
      .add("measurements", u.measurements)
      .add("total_poses", u.total_poses)
      .add("total_measurements", u.total_measurements)
      .add("agents", u.agents)
      .add("moved", u.moved)
      .add("largest_block", u.largest_block)
      .add("smallest_block", u.smallest_block)
      .add("cut", u.cut)
      .add("rounds", u.rounds)
      .add("ms", u.ms)
      .add("cpu_s", u.cpu_s)
      .add("setup_s", u.setup_s)
      .add("rounds_cpu_s", u.rounds_cpu_s)
      .add("critical_path_cpu_s", u.critical_path_cpu_s)
      .add("latency_s", u.latency_s)
      .add("latency_cpu_s", u.latency_cpu_s)
      .add("newest_publication_s", u.newest_publication_s)
      .add("message_steps", u.rounds + u.newton_message_steps)
      .add("bytes", static_cast<std::size_t>(u.bytes))
      .add("grad_norm", u.grad_norm)
      .add("stop_reason", u.stop_reason)
      .add("newton_steps", u.newton_steps)
      .add("newton_cg_iterations", u.newton_cg_iterations)
      .add("newton_message_steps", u.newton_message_steps)
      .add("relaxation_cost", u.relaxation_cost)
      .add("factorizations", u.factorizations)
      .add("factor_flops", u.factor_flops)
      .add("blocks_built", u.blocks_built)
      .add("merges", u.merges)
      .add("merge_poses_moved", u.merge_poses_moved);
  return j;
}

// Writes through a temporary file and a rename: a reader of a summary rewritten while the run
// goes on never sees half of one.
void write_replacing(const std::string& path, const std::string& text) {
  if (path == "-") return write_output(path, text);
  const std::string tmp = path + ".partial";
  write_output(tmp, text);
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw InputError("cannot write " + path + " (rename from " + tmp + " failed)");
}

struct Checkpoint {
  double time_s = 0.0;
  PoseGraph graph;
  double cost = 0.0;
  double optimum = 0.0;
  // The step's estimates (StepPoint) with their costs on `graph`, its newest data's wait for
  // the step, and the step's own latencies (from its oldest data, to its end).
  std::vector<StepPointCost> points;
  double wait_s = 0.0;
  double step_latency_s = 0.0, step_latency_cpu_s = 0.0;
  GapLatency gap;  // against `optimum`, after the run
};

}  // namespace

int solve_online_command(const Arguments& a, const std::string& graph_path,
                         std::chrono::steady_clock::time_point start) {
  OnlineOptions options;
  options.solver.algorithm = parse_algorithm(a.get_or("algorithm", "irbcd"));
  options.solver.grad_norm_tol = a.get_double("grad-tol", options.solver.grad_norm_tol);
  options.solver.max_rounds = static_cast<int>(a.get_long("max-rounds", options.solver.max_rounds));
  options.solver.rank = static_cast<int>(a.get_long("rank", options.solver.rank));
  options.certify_at_end = !a.has("no-certify");
  options.solver.staircase.certificate.max_iterations = static_cast<int>(
      a.get_long("certify-iters", options.solver.staircase.certificate.max_iterations));
  options.real_time = a.has("real-time");
  options.certify_every_s = a.get_double("certify-every", 0.0);
  options.step_every_s = a.get_double("step-every", 0.0);
  options.first_step_on_grown_factors = first_step_on_grown_factors_of(a);
  options.rebalance = parse_rebalance_options(a);
  options.solver.threads = static_cast<int>(a.get_long("threads", options.solver.threads));
  options.solver.block_update.tangent_split_dots = tangent_split_dots_of(a);
  parse_growth_and_local_rounds(a, options);
  {
    const std::string step_solver = a.get_or("step-solver", "newton");
    if (step_solver != "newton" && step_solver != "rounds")
      throw InputError("option --step-solver: '" + step_solver + "' is not one of newton, rounds");
    options.newton_steps = step_solver == "newton";
    options.newton_after_grad_tol = a.get_double("newton-after", options.newton_after_grad_tol);
    parse_step_coarse_options(a, options);
  }
  options.validate();
  ReplayOptions replay;
  replay.rate = a.get_double("rate", replay.rate);
  replay.speedup = a.get_double("speedup", replay.speedup);
  for (const std::string& s : a.get_list("start")) {
    try {
      replay.start_s.push_back(std::stod(s));
    } catch (const std::exception&) {
      throw InputError("option --start: '" + s + "' is not a number");
    }
  }
  replay.validate();
  const long checkpoints = a.get_long("checkpoints", 0);
  if (checkpoints < 0) throw InputError("option --checkpoints: must be >= 0");
  const double gap_bound = a.get_double("gap-bound", 1e-3);
  if (!(gap_bound > 0) || !std::isfinite(gap_bound))
    throw InputError("option --gap-bound: must be a finite number > 0");

  const auto files = robot_files_of(graph_path);
  const long robots = a.get_long("robots", 1);
  if (!files.empty() && a.has("robots"))
    throw InputError("option --robots: robot files say who owns what; use it with one g2o file");
  const runtime::ReplayInput input =
      files.empty() ? runtime::replay_input_from_file(
                          graph_path, robots > 0 ? static_cast<std::size_t>(robots) : 0)
                    : runtime::replay_input_from_robot_files(files);
  ReplayPlan plan = plan_replay(input.graph, input.robot_of_pose, replay);
  if (a.has("until")) {
    const double until = a.get_double("until", 0.0);
    if (!(until >= 0) || !std::isfinite(until))
      throw InputError("option --until: must be a finite number of seconds >= 0");
    plan.batches.erase(std::find_if(plan.batches.begin(), plan.batches.end(),
                                    [&](const StreamBatch& b) { return b.stamp > until; }),
                       plan.batches.end());
  }

  // Steps sampled for checkpoints: every `every`-th step that did work (the count is known
  // only afterwards, so sample on the number of batches instead: one per tick).
  const std::size_t every =
      checkpoints > 0
          ? std::max<std::size_t>(1, plan.batches.size() / static_cast<std::size_t>(checkpoints))
          : 0;
  std::vector<Checkpoint> marks;
  std::size_t seen_batches = 0, next_mark = every;
  OnlineBaseline baseline(a, plan, input.graph.d, options);

  const bool progress = !a.has("no-progress");
  const double progress_interval = a.get_double("progress-interval", 10.0);
  if (!(progress_interval >= 0) || !std::isfinite(progress_interval))
    throw InputError("option --progress-interval: must be a finite number of seconds >= 0");
  const std::optional<std::string> json_path = a.get("json");
  const double stream_end_s = plan.batches.empty() ? 0.0 : plan.batches.back().stamp;
  auto elapsed_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  // Phases after the steps are announced only in runs long enough to have printed a line.
  bool printed = false;
  auto say = [&](const std::string& line) {
    if (!progress) return;
    std::fprintf(stderr, "tessera solve --online: %s; %.1f s wall\n", line.c_str(), elapsed_s());
    std::fflush(stderr);
    printed = true;
  };

  // The summary's fields known while the steps run; `res` (the finished run) adds the rest.
  std::vector<OnlineUpdate> steps;
  double wall_s = 0.0;
  auto summary = [&](const OnlineResult* res) {
    std::vector<JsonObject> updates, cps, certs;
    int rounds = 0;
    std::uint64_t bytes = 0;
    double cpu_s = 0.0, setup_s = 0.0, rounds_cpu_s = 0.0;
    std::vector<double> gaps, gap_latency_s, gap_latency_cpu_s, gap_cg;
    const std::vector<OnlineUpdate>& done = res ? res->updates : steps;
    for (const auto& u : done) {
      updates.push_back(update_json(u));
      rounds += u.rounds;
      bytes += u.bytes;
      cpu_s += u.cpu_s;
      setup_s += u.setup_s;
      rounds_cpu_s += u.rounds_cpu_s;
    }
    for (const auto& c : marks) {
      JsonObject j;
      j.add("time_s", c.time_s)
          .add("poses", c.graph.num_poses)
          .add("measurements", c.graph.measurements.size())
          .add("cost", c.cost);
      j.add("wait_s", c.wait_s)
          .add("step_latency_s", c.step_latency_s)
          .add("step_latency_cpu_s", c.step_latency_cpu_s);
      if (res) {
        j.add("optimum", c.optimum).add("rel_gap", (c.cost - c.optimum) / c.optimum);
        gaps.push_back((c.cost - c.optimum) / c.optimum);
        // null where no estimate of the step was within the bound
        j.add("time_to_gap_s", c.gap.wall_s).add("time_to_gap_cpu_s", c.gap.cpu_s);
        j.add("time_to_stay_s", c.gap.stays ? c.wait_s + c.points[*c.gap.stays].wall_s
                                            : std::numeric_limits<double>::infinity());
        // The load-free companion: the step's CG iterations up to that point.
        const double cg = c.gap.first ? c.points[*c.gap.first].cg_iterations
                                      : std::numeric_limits<double>::infinity();
        j.add("cg_to_gap", cg);
        // And the fixed cost before it: the blocks' factorizations.
        j.add("factorizations_to_gap",
              c.gap.first ? static_cast<double>(c.points[*c.gap.first].factorizations)
                          : std::numeric_limits<double>::infinity());
        gap_latency_s.push_back(c.gap.wall_s);
        gap_latency_cpu_s.push_back(c.gap.cpu_s);
        gap_cg.push_back(cg);
      }
      std::vector<JsonObject> points;
      for (std::size_t k = 0; k < c.points.size(); ++k) {
        JsonObject p;
        p.add("at", c.points[k].at)
            .add("wall_s", c.points[k].wall_s)
            .add("cpu_s", c.points[k].cpu_s)
            .add("newton_steps", c.points[k].newton_steps)
            .add("cg_iterations", c.points[k].cg_iterations)
            .add("factorizations", c.points[k].factorizations)
            .add("cost", c.points[k].cost);
        if (res) p.add("rel_gap", c.gap.rel_gaps[k]);
        points.push_back(std::move(p));
      }
      j.add("points", points);
      cps.push_back(std::move(j));
    }
    const std::vector<OnlineCertificate> no_certificates;
    for (const auto& c : res ? res->certificates : no_certificates) {
      JsonObject o;
      o.add("time_s", c.time_s)
          .add("poses", c.poses)
          .add("certified", c.certified)
          .add("min_eigenvalue", c.min_eigenvalue)
          .add("cpu_s", c.cpu_s)
          .add("escaped", c.escaped)
          .add("cost_before", c.cost_before)
          .add("cost_after", c.cost_after);
      certs.push_back(std::move(o));
    }
    const std::vector<double> no_latency;
    const std::vector<double>& latency = res ? res->batch_latency_s : no_latency;
    JsonObject j;
    j.add("graph", graph_path)
        .add("mode", "online")
        .add("complete", res != nullptr)
        .add("algorithm", algorithm_name(options.solver.algorithm))
        .add("d", input.graph.d)
        .add("robots", input.robots)
        .add("poses", res ? res->graph.num_poses : (done.empty() ? 0 : done.back().total_poses))
        .add("measurements", res ? res->graph.measurements.size()
                                 : (done.empty() ? 0 : done.back().total_measurements))
        .add("batches", plan.batches.size())
        .add("rate", replay.rate)
        .add("speedup", replay.speedup)
        .add("real_time", options.real_time)
        .add("step_every_s", options.step_every_s);
    add_online_solver_options(j, options);
    j.add("rebalance", rebalance_options_json(options.rebalance))
        .add("grad_tol", options.solver.grad_norm_tol)
        .add("steps", done.size())
        .add("rounds", res ? res->rounds : rounds)
        .add("bytes", static_cast<std::size_t>(res ? res->bytes : bytes))
        .add("cpu_s", res ? res->cpu_s : cpu_s)
        .add("setup_s", setup_s)
        .add("rounds_cpu_s", rounds_cpu_s);
    if (res) {
      j.add("latency_median_s", percentile(latency, 0.5))
          .add("latency_p95_s", percentile(latency, 0.95))
          .add("latency_cpu_median_s", percentile(res->batch_latency_cpu_s, 0.5))
          .add("latency_cpu_p95_s", percentile(res->batch_latency_cpu_s, 0.95))
          .add("max_checkpoint_rel_gap",
               gaps.empty() ? 0.0 : *std::max_element(gaps.begin(), gaps.end()))
          .add("gap_bound", gap_bound)
          .add("gap_latency_median_s", percentile(gap_latency_s, 0.5))
          .add("gap_latency_p95_s", percentile(gap_latency_s, 0.95))
          .add("gap_latency_cpu_median_s", percentile(gap_latency_cpu_s, 0.5))
          .add("gap_latency_cpu_p95_s", percentile(gap_latency_cpu_s, 0.95))
          .add("gap_cg_median", percentile(gap_cg, 0.5))
          .add("gap_cg_p95", percentile(gap_cg, 0.95))
          .add("gap_latency_missed",
               static_cast<std::size_t>(std::count_if(gap_latency_s.begin(), gap_latency_s.end(),
                                                      [](double t) { return !std::isfinite(t); })))
          .add("repartitions", res->repartitions)
          .add("poses_moved", res->poses_moved)
          .add("final_rounds", res->final_rounds)
          .add("cost", res->cost)
          .add("grad_norm", res->grad_norm)
          .add("certified", res->certified)
          .add("min_eigenvalue", res->min_eigenvalue);
    }
    j.add("wall_s", res ? wall_s : elapsed_s());
    baseline.add_to(j);
    j.add("certificates", certs).add("checkpoints", cps).add("updates", updates);
    return j.str();
  };

  auto last_line = std::chrono::steady_clock::now();
  // A re-solve of a large graph can take minutes: announced when the last line is old or the
  // last re-solve was long.
  double last_resolve_cpu_s = 0.0, resolve_cpu_before = 0.0;
  baseline.before_resolve = [&](std::size_t poses, std::size_t measurements) {
    last_resolve_cpu_s = baseline.measured_cpu_s() - resolve_cpu_before;
    resolve_cpu_before = baseline.measured_cpu_s();
    const auto now = std::chrono::steady_clock::now();
    if (!progress || (std::chrono::duration<double>(now - last_line).count() < progress_interval &&
                      last_resolve_cpu_s < progress_interval))
      return;
    last_line = now;
    say("baseline re-solve " + std::to_string(baseline.resolved()) + " of ~" +
        std::to_string(baseline.expected()) + " from scratch on " + std::to_string(poses) +
        " poses, " + std::to_string(measurements) + " measurements");
  };
  double step_cpu_s = 0.0;
  // The steps that may be checkpoints keep their estimates (a copy of the iterate per point):
  // a step that turns out not to be one (the robots have not met) drops them at the next.
  auto before_step = [&](OnlineEngine& engine, std::size_t batches) {
    engine.keep_step_points(every > 0 && seen_batches + batches >= next_mark);
  };
  auto observer = [&](const OnlineEngine& engine, const OnlineUpdate& u) {
    seen_batches += u.batches;
    steps.push_back(u);
    step_cpu_s += u.cpu_s;
    const PoseGraph& g = engine.stream().graph();
    if (every > 0 && seen_batches >= next_mark) {
      const std::vector<Pose> estimate = engine.estimate();
      if (!estimate.empty()) {  // empty until the robots met (no common frame)
        next_mark += every;
        Checkpoint c;
        c.time_s = u.time_s;
        c.graph = g;
        c.cost = evaluate_objective(g, estimate);
        c.points = cost_step_points(g, engine.step_points());
        c.wait_s = u.time_s - u.newest_publication_s;
        c.step_latency_s = u.latency_s;
        c.step_latency_cpu_s = u.latency_cpu_s;
        marks.push_back(std::move(c));
      }
    }
    baseline.observe(engine, u);
    const auto now = std::chrono::steady_clock::now();
    if (progress && std::chrono::duration<double>(now - last_line).count() >= progress_interval) {
      last_line = now;
      char line[320];
      std::snprintf(line, sizeof line,
                    "step %zu, stream %.2f of %.2f s, %zu poses, %zu measurements, steps' CPU "
                    "%.1f s (this step %.2f s, %d Newton CG)",
                    steps.size(), u.time_s, stream_end_s, u.total_poses, u.total_measurements,
                    step_cpu_s, u.cpu_s, u.newton_cg_iterations);
      std::string text = line;
      if (baseline.expected() > 0) {
        std::snprintf(line, sizeof line, "; baseline %d of ~%ld re-solves, %.1f CPU-s",
                      baseline.resolved(), baseline.expected(), baseline.measured_cpu_s());
        text += line;
      }
      say(text);
      if (json_path && *json_path != "-") write_replacing(*json_path, summary(nullptr));
    }
    if (printed && seen_batches == plan.batches.size())
      say("all " + std::to_string(plan.batches.size()) + " batches absorbed in " +
          std::to_string(steps.size()) + " steps; final solve" +
          (options.certify_at_end ? " and certificate" : "") + " on " +
          std::to_string(g.num_poses) + " poses");
  };
  const OnlineResult res = run_online(input.graph.d, plan.batches, options, observer, before_step);
  wall_s = elapsed_s();

  for (std::size_t k = 0; k < marks.size(); ++k) {
    if (printed)
      say("checkpoint " + std::to_string(k + 1) + " of " + std::to_string(marks.size()) +
          ": the optimum of the graph of " + std::to_string(marks[k].graph.num_poses) +
          " poses (centralized solver, offline)");
    marks[k].optimum = solve_centralized(marks[k].graph).cost;
    marks[k].gap = gap_latency(marks[k].points, marks[k].optimum, gap_bound, marks[k].wait_s);
  }
  const std::vector<double>& latency = res.batch_latency_s;
  std::printf(
      "%s online: %zu poses, %zu measurements, %zu robots, %zu steps, %d rounds; "
      "latency median %.4f s, p95 %.4f s; final cost %.10g, %s, %.3f s\n",
      graph_path.c_str(), res.graph.num_poses, res.graph.measurements.size(), input.robots,
      res.updates.size(), res.rounds, percentile(latency, 0.5), percentile(latency, 0.95), res.cost,
      res.certified ? (*res.certified ? "certified optimal" : "NOT certified")
                    : "not certified (skipped)",
      wall_s);
  if (json_path) write_replacing(*json_path, summary(&res));
  return 0;
}

}  // namespace tessera::cli
