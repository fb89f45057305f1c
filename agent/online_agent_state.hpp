#pragma once
// What an online agent (agent/online_agent.cpp) knows between epochs: its view of the graph,
// who takes part, its block and the figures of its summary. Shared by the transport side
// (agent/online_link.hpp: reading and waiting) and the decisions (agent/online_epoch_step.hpp);
// it holds no DDS entity.

#include <chrono>
#include <cstdint>
#include <ctime>

#include "agent/online_agent_options.hpp"
#include "agent/online_agent_summary.hpp"
#include "agent/online_batch_arrivals.hpp"
#include "agent/online_block_solver.hpp"
#include "agent/online_solve_outcome.hpp"
#include "runtime/online_agent_view.hpp"
#include "runtime/online_membership.hpp"

namespace tessera::agent {

using OnlineClock = std::chrono::steady_clock;

struct OnlineAgentState {
  explicit OnlineAgentState(const OnlineAgentOptions& options)
      : o(options),
        view(options.id, options.robots, options.online),
        membership(options.robots),
        block(options.online) {}

  std::uint32_t me() const { return static_cast<std::uint32_t>(o.id); }
  const std::set<std::uint32_t>& members() const { return membership.members(epoch); }
  bool member() const { return membership.is_member(me(), epoch); }
  bool lead() const { return membership.lead_of(epoch) == me(); }
  /// Seconds since the run's start.
  double now_s() const { return std::chrono::duration<double>(OnlineClock::now() - start).count(); }

  OnlineAgentOptions o;
  runtime::OnlineAgentView view;
  runtime::OnlineMembership membership;
  OnlineBlockSolver block;  // this agent's block, grown from solve to solve
  OnlineClock::time_point start = OnlineClock::now();
  std::uint32_t epoch = 0;
  bool converged = true;
  bool finishing = false;  // the stream is over: the epoch after the final solve ends the run
  double next_certificate_s = 0.0, last_publish_s = -1e300;
  bool changed_since_certificate = false;
  BatchArrivals arrivals;
  OnlineFigures fig;
  SolveOutcome final_solve;
  double last_grad_norm = 0.0;
};

/// The process's CPU time, seconds.
inline double cpu_now() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

}  // namespace tessera::agent
