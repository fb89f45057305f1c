#pragma once
// This agent's block of an online run's graph: its problem, kept from solve to solve and grown
// with the new data (LiveBlocks), one solve of it from the current estimate, and the block's
// poses that go out with the next report. The messages of the round protocol are the agent's
// (agent/online_link.hpp): the solve hands it the CertifiedAgent to drive.

#include <cstdint>
#include <functional>
#include <memory>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/online/online_engine.hpp>
#include <vector>

#include "agent/online_solve_outcome.hpp"
#include "runtime/online_agent_view.hpp"

namespace tessera::agent {

class OnlineBlockSolver {
 public:
  /// Drives the round protocol of `agent` (this agent's block `block` of the solve's layout)
  /// until it is done.
  using RunRounds = std::function<void(CertifiedAgent& agent, std::uint32_t block)>;

  explicit OnlineBlockSolver(const OnlineOptions& options) : options_(options) {}

  /// Solves the graph `view` holds from its estimate, this agent's block by `run_rounds`;
  /// `certify` asks for a certificate, `climb` lets it climb the staircase. The block's poses
  /// go into `view` (and own_ids/own_data) also when a take-over interrupts the rounds
  /// (TakeoverNeeded propagates). Nothing is solved (a zero outcome) while the block is empty.
  SolveOutcome solve(runtime::OnlineAgentView& view, bool certify, bool climb,
                     const RunRounds& run_rounds);

  /// The block's poses of the last solve: full-graph ids, their rank x (d+1) blocks in order.
  const std::vector<std::uint32_t>& own_ids() const { return own_ids_; }
  const std::vector<double>& own_data() const { return own_data_; }
  int own_rank() const { return own_rank_; }
  /// The robot (= agent) of block `b` of the last solve's layout, -1 when there is none.
  long robot_of_block(const runtime::OnlineAgentView& view, std::uint32_t b) const;

 private:
  void keep_own_poses(runtime::OnlineAgentView& view, const AgentState& state,
                      const std::vector<std::size_t>& ids);

  OnlineOptions options_;
  std::unique_ptr<LiveBlocks> live_;
  std::vector<std::uint32_t> own_ids_;
  std::vector<double> own_data_;
  int own_rank_ = 0;
};

}  // namespace tessera::agent
