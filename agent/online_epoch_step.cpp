#include "agent/online_epoch_step.hpp"

#include <cstdio>
#include <string>
#include <tessera/graph/connectivity.hpp>
#include <utility>
#include <vector>

namespace tessera::agent {

namespace {

// What the members' reports of the epoch say together.
struct EpochReports {
  std::vector<Watermarks> held;  // per member
  bool all_converged = true;
  bool certify_now = false;  // the lead asks for a certificate of the grown graph
};

SolveOutcome solve(OnlineAgentState& s, OnlineLink& link, bool certify, bool climb = true) {
  return s.block.solve(s.view, certify, climb, [&](CertifiedAgent& agent, std::uint32_t me) {
    link.run_rounds(agent, me);
  });
}

bool solve_converged(const OnlineAgentState& s, const SolveOutcome& out) {
  return out.grad_norm <= s.o.online.solver.grad_norm_tol || out.stop_reason == "stalled";
}

// A member's report: what it holds, its vote, its block's poses; the lead's also asks for a
// certificate (--certify-every) and names the next epoch's members.
void send_own_report(OnlineAgentState& s, OnlineLink& link) {
  transport::OnlineReportSample mine;
  mine.epoch = s.epoch;
  mine.sender = s.me();
  mine.held = s.view.held();
  mine.converged = s.converged;
  mine.rank = s.block.own_rank();
  mine.dim = s.view.dim();
  mine.pose_ids = s.block.own_ids();
  mine.data = s.block.own_data();
  if (s.lead()) {
    if (s.o.certify_every_s > 0 && s.changed_since_certificate &&
        s.now_s() >= s.next_certificate_s) {
      mine.certify = true;
      s.next_certificate_s = s.now_s() + s.o.certify_every_s;
      s.changed_since_certificate = false;
    }
    // An agent that said hello and died before it was admitted is not admitted.
    mine.next_members = s.membership.next_members(
        s.epoch, s.o.continue_on_loss ? link.lost_agents() : std::vector<std::uint32_t>{});
  }
  link.send_report(mine);
}

// Applies the other members' block poses to the view (the estimate is whole afterwards).
EpochReports read_reports(OnlineAgentState& s, OnlineLink& link) {
  EpochReports out;
  auto& reports = link.reports(s.epoch);
  for (const auto& [sender, r] : reports) {
    if (s.members().count(sender) == 0) continue;
    if (sender != s.me() && r.dim != 0) {
      if (s.view.dim() == 0) link.pump_stream();  // the block's graph must be there first
      s.view.apply_block(r.pose_ids, r.data, r.rank);
    }
    out.held.push_back(r.held);
    out.all_converged = out.all_converged && r.converged;
  }
  const std::uint32_t lead = s.membership.lead_of(s.epoch);
  out.certify_now = reports.count(lead) > 0 && reports[lead].certify;
  return out;
}

void print_entered(const OnlineAgentState& s, const runtime::EnteredData& in, bool member) {
  std::string who;
  for (std::uint32_t m : s.members()) who += " " + std::to_string(m);
  std::fprintf(stderr, "agent %d: epoch %u members%s: +%zu poses +%zu measurements%s%s\n", s.o.id,
               s.epoch, who.c_str(), in.poses, in.measurements, member ? "" : " (following)",
               s.converged ? " converged" : "");
}

// Every robot's last batch entered: the final solve (certified with --certify at the end);
// the next epoch's reports carry its poses and end the run.
void final_step(OnlineAgentState& s, OnlineLink& link, bool member, double cpu_start) {
  if (member) s.final_solve = solve(s, link, s.o.online.certify_at_end);
  if (s.o.verbose)
    std::fprintf(stderr, "agent %d: final solve: %d rounds, certified %s\n", s.o.id,
                 s.final_solve.rounds, s.final_solve.certified.value_or(false) ? "yes" : "no");
  s.fig.cpu_s += cpu_now() - cpu_start;
  s.finishing = true;
}

// The lead asked for a certificate of the grown graph (connected): a certified solve at the
// current rank.
void certify_step(OnlineAgentState& s, OnlineLink& link, double step_start, double cpu_start) {
  const SolveOutcome c = solve(s, link, true, false);
  s.converged = solve_converged(s, c);
  s.fig.cpu_s += cpu_now() - cpu_start;
  s.fig.rounds += c.rounds;
  cli::JsonObject j;
  j.add("epoch", static_cast<long long>(s.epoch))
      .add("time_s", step_start)
      .add("poses", s.view.stream()->graph().num_poses)
      .add("certified", c.certified)
      .add("min_eigenvalue", c.min_eigenvalue)
      .add("rounds", c.rounds)
      .add("ms", 1000.0 * (s.now_s() - step_start));
  s.fig.certificates.push_back(std::move(j));
}

// Batches entered per robot 0..robots-1 (the epoch's absorption watermarks).
std::vector<std::size_t> entered_per_robot(const OnlineAgentState& s) {
  std::vector<std::size_t> out(static_cast<std::size_t>(s.o.robots), 0);
  for (const auto& [robot, count] : s.view.entered())
    if (robot < out.size()) out[robot] = static_cast<std::size_t>(count);
  return out;
}

// The summary's `updates` entry of a step that entered `in` and solved (or skipped) it.
cli::JsonObject update_json(const OnlineAgentState& s, const runtime::EnteredData& in,
                            const SolveOutcome& out, double step_start, double step_end,
                            double step_cpu, double oldest) {
  const GraphStream& g = *s.view.stream();
  cli::JsonObject u;
  u.add("epoch", static_cast<long long>(s.epoch))
      .add("time_s", step_start)
      .add("batches", in.batches)
      .add("poses", in.poses)
      .add("measurements", in.measurements)
      .add("total_poses", g.graph().num_poses)
      .add("total_measurements", g.graph().measurements.size())
      .add("agents", static_cast<long long>(s.members().size()))
      .add("moved", in.moved)
      .add("largest_block", in.largest_block)
      .add("smallest_block", in.smallest_block)
      .add("cut", in.cut)
      .add("entered", entered_per_robot(s))
      .add("rounds", out.rounds)
      .add("newton_steps", out.newton_steps)
      .add("newton_cg_iterations", out.newton_cg_iterations)
      .add("newton_message_steps", out.newton_message_steps)
      .add("coarse_unknowns", out.coarse_unknowns)
      .add("ms", 1000.0 * (step_end - step_start))
      .add("latency_s", step_end - oldest)
      .add("cpu_s", step_cpu)
      .add("latency_cpu_s", step_start - oldest + step_cpu)
      .add("grad_norm", out.grad_norm)
      .add("stop_reason", out.stop_reason);
  return u;
}

// A solve of the grown graph, or its skip when nothing moved the optimum.
void solve_step(OnlineAgentState& s, OnlineLink& link, const runtime::EnteredData& in,
                double step_start, double cpu_start) {
  // Every new measurement only placed a new pose (odometry, mostly) and every member voted
  // converged in its report: each new measurement has zero residual at the composed poses,
  // so f and its gradient are what they were. Every member sees the same votes and the same
  // entered data, so all skip the solve together, without a message of their own; the new
  // poses join their blocks at the next solve.
  const bool unchanged = s.converged && in.composed == in.measurements;
  SolveOutcome out;
  if (unchanged) {
    out.stop_reason = "unchanged";
    out.grad_norm = s.last_grad_norm;
  } else {
    out = solve(s, link, false);
    if (s.o.verbose)
      std::fprintf(stderr, "agent %d: solve: %d rounds, gradient norm %g (%s)\n", s.o.id,
                   out.rounds, out.grad_norm, out.stop_reason.c_str());
    s.converged = solve_converged(s, out);
    s.last_grad_norm = out.grad_norm;
    ++s.fig.solves;
  }
  const double step_end = s.now_s();
  const double step_cpu = cpu_now() - cpu_start;
  s.fig.cpu_s += step_cpu;
  s.fig.rounds += out.rounds;
  const double oldest =
      s.arrivals.absorbed(*s.view.stream(), step_end, step_start, s.fig.batch_latency_s, step_cpu,
                          &s.fig.batch_latency_cpu_s);
  s.fig.updates.push_back(update_json(s, in, out, step_start, step_end, step_cpu, oldest));
}

// After the reports: publishes, enters what every member holds and acts on it. Returns false
// once the run is over.
bool enter_and_act(OnlineAgentState& s, OnlineLink& link, const EpochReports& reports,
                   bool member) {
  // The estimate is whole here (every block's poses of the last solve arrived).
  if (s.finishing) {
    if (s.o.publish_every_s > 0 || !s.o.tum_dir.empty()) link.publish_estimate();
    return false;
  }
  if (s.o.publish_every_s > 0 && s.now_s() - s.last_publish_s >= s.o.publish_every_s)
    link.publish_estimate();
  const Watermarks decision = s.membership.entering(reports.held, s.epoch);
  // The members hold what they decided; a joiner following missed epochs may not yet.
  link.wait_to_hold(decision, true);
  const double step_start = s.now_s();
  const double cpu_start = cpu_now();
  const runtime::EnteredData in = s.view.enter(decision);
  const bool changed = in.poses > 0 || in.measurements > 0;
  if (s.o.verbose) print_entered(s, in, member);
  link.drop_reports(s.epoch);
  if (s.view.stream_over()) {
    final_step(s, link, member, cpu_start);
    return true;
  }
  if (!member) return true;  // a follower only builds the members' graph
  if (changed) s.changed_since_certificate = true;
  if (reports.certify_now && count_components(s.view.stream()->graph()) == 1) {
    certify_step(s, link, step_start, cpu_start);
  } else if (!changed && s.converged) {
    // Idle: a blocking wait for new data (ours, another agent's next report, or a hello
    // for the lead to admit); nothing is sent meanwhile.
    ++s.fig.idle_waits;
    link.wait_for_news(decision);
  } else {
    solve_step(s, link, in, step_start, cpu_start);
  }
  return true;
}

}  // namespace

bool epoch_step(OnlineAgentState& s, OnlineLink& link) {
  link.pump_stream();
  link.pump_channel();
  const bool member = s.member();
  if (member) {
    link.wait_matched();
    send_own_report(s, link);
  }
  link.wait_for_reports();
  const EpochReports reports = read_reports(s, link);
  s.converged = reports.all_converged;
  const bool go_on = enter_and_act(s, link, reports, member);
  if (go_on) ++s.epoch;
  return go_on;
}

}  // namespace tessera::agent
