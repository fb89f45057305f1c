#pragma once
// A solve whose agents' Newton trial points are watched from outside the agents: the online
// engine records the estimates a step passes through (online/step_points.hpp) from the same
// agents and driver as solve_distributed_with_states, not from a copy of that driver.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <tessera/distributed/distributed_solver.hpp>
#include <vector>

namespace tessera {

/// Called with each Newton trial point of each agent (CertifiedAgent::set_trial_observer):
/// the agent's block id and its block of the trial point, in the order of the refinements'
/// traces (one call per NewtonRefineStep of every agent). From the thread that handles that
/// agent: with DistributedOptions::threads > 1, concurrently for different agents.
using TrialPointWatch = std::function<void(int block, const Eigen::MatrixXd& Y)>;

/// solve_distributed_with_states with `watch` given every agent's trial points (an empty
/// `watch`: exactly solve_distributed_with_states).
DistributedResult solve_distributed_watching_trials(
    const PoseGraph& graph, const BlockLayout& layout, const std::vector<AgentState*>& states,
    const DistributedOptions& options, const TrialPointWatch& watch,
    double known_grad_norm = std::numeric_limits<double>::quiet_NaN());

}  // namespace tessera
