#pragma once
// Continuing a distributed solve after agents are lost for good, in one process: the lost
// agents' poses go to the survivors (survivor_repartition.hpp), the lost agents' part of the
// iterate comes from its replica (possibly a few rounds stale), and the survivors' rounds start
// again from that combined iterate. The DDS runtime does the same across processes; this is
// the reference it is checked against, and the place the convergence argument is tested.
//
// Why a stale replica does not change the answer: the new run is a fresh run of the same
// algorithm from a different starting point. Any point of the lifted manifold (each block
// [Y_i | p_i] with Y_i in St(d, r)) is a valid start, and the replica is such a point (it was an
// iterate). The survivors' run converges to a first-order critical point of the same problem;
// at rank r above the problem's tightness threshold that point is the global optimum, so the
// rounded cost reaches f* whatever the staleness. Staleness only costs rounds.

#include <Eigen/Core>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/partition/survivor_repartition.hpp>
#include <vector>

namespace tessera {

struct LossRecoveryResult {
  SurvivorRepartitionResult repartition;  ///< Who owns what now (owner = old agent ids).
  DistributedResult run;                  ///< The survivors' run (agents 0..S-1 = survivors).
  Eigen::MatrixXd start;                  ///< The iterate the survivors started from.
};

/// `old_assignment`: agent (0..num_agents-1) of every pose before the loss; `lost`: the lost
/// agents; `current`: the survivors' current lifted iterate (r x (d+1)n, global order; columns
/// of lost agents' poses are ignored); `replica`: the lost agents' replicated lifted poses
/// (same shape; only their columns are read). Throws InputError on inconsistent shapes or ids.
LossRecoveryResult continue_after_loss(const PoseGraph& graph,
                                       const std::vector<int>& old_assignment, int num_agents,
                                       const std::vector<int>& lost, const Eigen::MatrixXd& current,
                                       const Eigen::MatrixXd& replica,
                                       const DistributedOptions& options,
                                       const SurvivorRepartitionOptions& repartition = {});

}  // namespace tessera
