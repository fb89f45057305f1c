#include "agent/online_agent.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/util/input_error.hpp>

#include "agent/online_agent_options.hpp"
#include "agent/online_agent_state.hpp"
#include "agent/online_agent_summary.hpp"
#include "agent/online_epoch_step.hpp"
#include "agent/online_link.hpp"
#include "agent/online_takeover_step.hpp"
#include "json_writer.hpp"
#include "transport/fastdds/teardown_guard.hpp"
#include "transport/online_channel.hpp"

namespace tessera::agent {

namespace {

// The online agent's run: epochs until the stream is over, a take-over whenever a member was
// lost, then the answer. The state lives in OnlineAgentState, the DDS side in OnlineLink and
// one epoch's decisions in epoch_step().
class OnlineAgent {
 public:
  explicit OnlineAgent(const OnlineAgentOptions& o) : state_(o), link_(state_) {
    state_.start = OnlineClock::now();  // the run's clock starts once the agent joined
  }

  int run();

 private:
  /// The survivors agree on what was lost, reach the same graph and move the lost blocks.
  void take_over();
  /// The lead's f of the rounded whole estimate (none while the graph is not connected).
  std::optional<double> round_estimate();
  void write_json(std::optional<double> cost);

  OnlineAgentState state_;
  OnlineLink link_;
};

int OnlineAgent::run() {
  // Membership: agent 0 starts alone (epoch 0) and admits every agent it has heard from at
  // the next epoch boundary (its report's next_members), so the run needs no start barrier
  // and an agent started late is taken in the same way. A joiner first follows the epochs it
  // missed from the reports (kept for late readers): the same entered batches and block
  // poses give it the members' graph and estimate.
  if (state_.me() != 0) {
    transport::OnlineReportSample hello;
    hello.epoch = transport::kHelloEpoch;
    hello.sender = state_.me();
    link_.send_report(hello);
  }
  for (;;) {
    try {
      if (!epoch_step(state_, link_)) break;
    } catch (const TakeoverNeeded&) {
      take_over();
    }
  }
  // The lead rounds the whole estimate (every block's poses arrived with the last reports).
  const bool lead = state_.lead();
  const std::optional<double> cost = lead ? round_estimate() : std::nullopt;
  link_.flush(5.0);
  if (!state_.o.json.empty()) write_json(lead ? cost : std::nullopt);
  return 0;
}

std::optional<double> OnlineAgent::round_estimate() {
  const PoseGraph& graph = state_.view.stream()->graph();
  if (graph.num_poses == 0 || count_components(graph) != 1) return std::nullopt;
  const std::vector<Pose> poses = round_solution(graph, state_.view.iterate());
  const double cost = evaluate_objective(graph, poses);
  SolveOutcome& final_solve = state_.final_solve;
  if (final_solve.relaxation_cost)
    final_solve.certified =
        estimate_certified(final_solve.certified, cost, *final_solve.relaxation_cost);
  return cost;
}

void OnlineAgent::take_over() {
  OnlineAgentState& s = state_;
  const double at = s.now_s();
  OwnVote mine;
  mine.me = s.me();
  mine.epoch = s.epoch;
  mine.entered = s.view.entered();
  mine.rank = s.block.own_rank();
  mine.dim = s.view.dim();
  mine.pose_ids = s.block.own_ids();
  mine.data = s.block.own_data();
  const TakeoverStepResult step = takeover_step(
      link_.channel(), s.view, s.members(), mine, s.o.timeout_s,
      [&] {
        link_.pump_channel();
        link_.pump_stream();
        return link_.take_votes();
      },
      [&](const Watermarks& target) { link_.wait_to_hold(target, false); });
  s.fig.report_bytes += step.vote.bytes_sent;
  // The run goes on at an epoch no survivor has used: leftovers of the abandoned one (its
  // messages, reports, the lead's admissions) are dropped.
  s.epoch = step.vote.next_epoch;
  s.membership.taken_over(step.vote.lost, step.vote.survivors, s.epoch);
  link_.drop_before(s.epoch);
  s.converged = false;  // the blocks changed: solve again
  s.finishing = false;  // a final solve the loss interrupted runs again
  s.fig.faults.push_back(
      lost_for_good_fault(step, at, s.now_s(), s.epoch,
                          s.view.stream() ? s.view.stream()->graph().num_poses : std::size_t{0}));
  if (s.o.verbose)
    std::fprintf(stderr,
                 "agent %d: took over the blocks of %zu lost agent(s): %zu poses moved, epoch %u\n",
                 s.o.id, step.vote.lost.size(), step.moves.moved, s.epoch);
}

void OnlineAgent::write_json(std::optional<double> cost) {
  OnlineSummaryState summary;
  summary.epochs = state_.epoch;
  summary.graph = state_.view.stream();
  summary.final_solve = state_.final_solve;
  summary.wall_s = state_.now_s();
  summary.cost = cost;
  if (const GraphStream* g = state_.view.stream()) {
    summary.final_blocks.assign(static_cast<std::size_t>(state_.o.robots), 0);
    for (int b : state_.view.owner()) {
      const std::uint32_t robot = g->robots()[static_cast<std::size_t>(b)];
      if (robot < summary.final_blocks.size()) ++summary.final_blocks[robot];
    }
    summary.final_cut = cut_measurements(g->graph(), state_.view.owner());
  }
  cli::write_output(state_.o.json, online_summary_json(state_.o, summary, state_.fig));
}

}  // namespace

bool wants_online(const std::vector<std::string>& argv) {
  return std::find(argv.begin(), argv.end(), "--online") != argv.end();
}

int online_agent_main(const std::vector<std::string>& argv) {
  std::unique_ptr<OnlineAgent> agent;
  int code = 0;
  try {
    if (std::find(argv.begin(), argv.end(), "--help") != argv.end()) {
      std::fputs(online_agent_usage(), stdout);
      return 0;
    }
    const OnlineAgentOptions o = parse_online_agent_options(argv);
    agent = std::make_unique<OnlineAgent>(o);
    code = agent->run();
  } catch (const InputError& e) {
    std::cerr << "tessera-agent: error: " << e.what() << "\n";
    code = 2;
  } catch (const std::exception& e) {
    std::cerr << "tessera-agent: run failed: " << e.what() << std::endl;
    code = 1;
  }
  // The result or the error is out; deleting the participants comes last and is bounded, since
  // Fast DDS 2.9 can hang or abort there while a peer's removal races with it
  // (transport/fastdds/teardown_guard.hpp): a hang must not keep a failed or finished agent alive.
  if (agent) {
    const transport::TeardownGuard guard(code, "tessera-agent", std::chrono::seconds(5));
    agent.reset();
  }
  return code;
}

}  // namespace tessera::agent
