#pragma once
// GNC-TLS around the distributed solvers (`tessera solve --algorithm irbcd|rbcd|rbcd++
// --robust gnc-tls`, in one process): each outer step is a warm-started distributed solve of
// the weighted problem; the weight of every measurement is computed by one agent, the
// *owner of its lower pose id* (assignment[min(i, j)]), from what that agent holds after a
// solve: its own lifted poses and its neighbours' public ones. The outer loop is the agents'
// own (robust/gnc_agent.hpp), run here by the in-process driver and over DDS by the agents'
// round loop: the same messages, the same iterates.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <tessera/robust/gnc_agent_result.hpp>
#include <tessera/robust/robust_options.hpp>
#include <vector>

namespace tessera {

struct GncDistributedOptions {
  /// Settings of every distributed solve. Inner solves run without certification, warm-started
  /// from the previous lifted iterate; the final solve of the inlier set certifies when
  /// solver.certify is on.
  DistributedOptions solver;
  RobustOptions robust;  ///< kPcmGnc: the consistency check first (GncAgentInput::pcm).
  /// Empty, or one flag per measurement: true = never down-weighted, like the known-inlier
  /// rule's measurements (a dpgo CSV file's is_known_inlier column).
  std::vector<bool> known_inlier_flags;
  /// Consider the distributed initialization of the known inliers alone (with the default
  /// rule: each robot's odometry chain, robots joined by their consecutive-id links) as the
  /// start besides solver.initialization; the agents take the one with the lower TLS cost (a
  /// vote, GncAgentInput::Y0_known). Unused when the known inliers do not connect the poses;
  /// false: always solver.initialization.
  bool known_inlier_start = true;
  /// The first inlier pass may start from solver.initialization of the kept set when that costs
  /// less than the GNC iterate (GncAgentInput::kept_set_start; chordal only).
  bool kept_set_start = true;
  /// With kept_set_start: once the passes end, before the final solve, the kept set's fresh
  /// start is voted again (the kept set's squared residuals at it against at the iterate); when
  /// it wins, the passes run again from it (a new pass budget), once. Why: the iterate the
  /// passes judged may sit in a fold that rough solves cannot leave, and then true closures stay
  /// cut (city10000, 50 % random outliers, 5 agents on id ranges: 716 of them, all with r^2 <=
  /// 0.21 at the clean optimum against c^2 = 41, and the final solve ended at 13,047 over a kept
  /// set whose optimum is 597). When the iterate is a converged solution of the kept set the
  /// vote keeps it: one gather and one vote, no rounds. The vote is skipped when its outcome is
  /// already known: the same kept set was voted on before (its fresh start is a function of the
  /// set, so its summed cost is the one that vote saw) and the last inlier pass, solved to the
  /// tolerance on that set, ended more than 1e-9 (relative) below that cost (its solve's summed
  /// cost, the same on every agent); the iterate would win (intel and CSAIL with 25 % random
  /// outliers: 393.6525 against 394.5375, 31.4703 against 31.4848), so the 4 message steps of
  /// the gather and the vote are saved and nothing else changes.
  bool final_kept_set_start = true;
  /// With kept_set_start: when a capped inlier pass changes nothing (the passes would next solve
  /// that set to the tolerance from their iterate), the kept set's fresh start is voted first,
  /// unless that set was voted on before; when it wins, the passes go on from it (capped, in the
  /// same budget), otherwise the set is solved to the tolerance from the iterate as without the
  /// vote. Why: capped passes from an iterate bent around the true closures GNC cut take them
  /// back a few at a time (city10000, 50 % random outliers, 5 agents on id ranges: 169, 37, 14,
  /// 3, 1, then 86, 39, ... until the pass budget ran out and the last fresh-start vote won
  /// with 682 still cut), while the fresh start of the first stalled set costs 6,787 over it
  /// against the iterate's 54,548 and its first pass takes back 815. There: the same exact,
  /// certified set in 13,446 message steps instead of 27,167 (rounds 6,025 instead of 12,864).
  /// One gather and one vote each time; docs/robust.md, "The stall vote".
  bool stall_kept_set_start = true;
  /// Most cluster probes after the re-check passes, >= 0 (0 = none, default: the probes of
  /// RobustOptions::recheck_probes alone). The distributed counterpart of
  /// GncCentralizedOptions::cluster_probes, in the same order and on the same rule: up to
  /// recheck_probes tail probes (the agents' own lists) first, then one cluster of kept closures
  /// side by side at a time (closure_clusters.hpp), then two clusters that share a stretch
  /// (each raised the TLS cost alone), last the return band together, then one closure of it at
  /// a time; each one kept only when the summed TLS cost falls, and after a kept one every
  /// candidate may be tried again. Every agent runs the same search on the same data (the
  /// endpoints of every measurement, the rejected set, the gathered verdict lists, the summed
  /// TLS costs), so all pick the same probe without a message (core/robust/gnc_cluster_search.hpp).
  /// Why: a run of wrong closures between two look-alike stretches bends the map until each of
  /// them fits, the true closures of the stretch are cut instead, and the agents' tail probes
  /// cut true and wrong closures alike (intel with group outliers; docs/robust.md).
  int cluster_probes = 0;
  ClosureClusterOptions clusters;  ///< Which kept closures form a cluster.
  /// Optional: called after every weight exchange with (agent, outer step, that agent's
  /// measurements by file position, the weights it uses for them); tests compare the two ends
  /// of every cut measurement with it.
  std::function<void(int, int, const std::vector<std::uint64_t>&, const std::vector<double>&)>
      weight_observer;
  void validate() const;  ///< Throws InputError naming the first bad field.
};

/// What one agent decides in an outer step.
struct AgentWeights {
  std::vector<std::size_t> measurements;  ///< The measurements it owns (ascending).
  std::vector<double> weights;            ///< Their new weights, same order.
  double max_residual_squared = 0;        ///< Over its owned non-known-inlier measurements.
  double weight_spread = 0;               ///< sum w (1 - w) over its measurements.
};

/// The agent that computes measurement m's weight: the owner of min(m.i, m.j).
int weight_owner(const Measurement& m, const std::vector<int>& assignment);

/// Agent `agent`'s step: residuals of its measurements at the lifted iterate X (r x (d+1)n,
/// global order; only the columns of its own poses and of the other ends of its measurements
/// are read) and, for mu > 0, their TLS weights (known inliers keep 1). With mu = 0 the
/// weights are all 1 (the residual maximum is what is wanted then). `flags`: empty or one
/// per measurement, true = known inlier (GncDistributedOptions::known_inlier_flags).
AgentWeights agent_weights(int agent, const PoseGraph& graph, const std::vector<int>& assignment,
                           const Eigen::MatrixXd& X, const RobustOptions& robust, double c2,
                           double mu, const std::vector<bool>& flags = {});

/// The run's decisions (rejected set, counts, threshold, the solves' message steps before the
/// final one) are GncAgentResult's, agent 0's (every agent holds the same).
struct GncDistributedResult : GncAgentResult {
  DistributedResult final_solve;  ///< The inlier-set solve (cost over kept measurements).
  std::vector<double> weights;    ///< Last weight of every measurement.
  int total_rounds = 0;           ///< Rounds of every solve, final included.
  /// Message steps of the final solve's Newton refinement (0 when no final solve runs: the
  /// last inlier pass is then the answer and its refinement is in refine_message_steps). The
  /// run's message steps in all: message_steps() below.
  int final_refine_message_steps = 0;
  int final_solve_stages = 0;     ///< Solve stages of the final solve (0 when none runs).
  std::uint64_t total_bytes = 0;  ///< Bytes of every solve plus the outer steps' votes.
  /// The longest chain of messages of the agents' run and then the final solve's
  /// (DeliveryStats::longest_chain).
  std::uint64_t longest_chain = 0;
  /// Measurements GNC had kept whose residual at an inlier set's solution was beyond the bound,
  /// rejected by the re-check passes (GncAgent::late_rejected()).
  std::size_t late_rejected = 0;
};

/// Every wait for peers of the run but its certificates' (GncAgentResult's message_steps()
/// with total_rounds, final_solve_stages and final_refine_message_steps): equal to
/// longest_chain without certification (every counted wait lies on one chain of messages).
long long message_steps(const GncDistributedResult& r);

/// The known inliers' start of distributed GNC (GncDistributedOptions::known_inlier_start): the
/// distributed initialization (with solver.robots, or `agents`, robots) of the measurements that
/// are known inliers by the rule or the flags, or nullopt when the option is off or those
/// measurements leave the poses unconnected.
std::optional<std::vector<Pose>> known_inlier_poses(const PoseGraph& graph,
                                                    const GncDistributedOptions& options,
                                                    int agents);

/// Runs GNC-TLS with the distributed solver on `assignment`'s blocks. Throws InputError on
/// bad options and, like solve_gnc_centralized(), when the kept measurements leave the poses
/// unconnected.
GncDistributedResult solve_gnc_distributed(const PoseGraph& graph,
                                           const std::vector<int>& assignment,
                                           const GncDistributedOptions& options);

}  // namespace tessera
