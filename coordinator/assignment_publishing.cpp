#include "coordinator/assignment_publishing.hpp"

#include <string>
#include <tessera/robust/robust_options.hpp>

#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

wire::PartitionAssignment make_assignment(const CoordinatorOptions& options,
                                          const RunStructure& structure,
                                          const PartitionStepResult& part) {
  wire::PartitionAssignment asg;
  asg.run_id(options.net.session.run_id);
  asg.num_agents(options.agents);
  asg.num_poses(static_cast<std::uint32_t>(structure.num_poses));
  asg.dim(static_cast<std::uint32_t>(structure.d));
  asg.rank(options.rank);
  asg.owner(part.owner);
  asg.edge_i(structure.edge_i);
  asg.edge_j(structure.edge_j);
  asg.algorithm(options.algorithm);
  asg.initialization(options.init);
  asg.max_rounds(options.max_rounds);
  asg.grad_norm_tolerance(options.grad_tol);
  asg.relative_cost_tolerance(options.rel_cost_tol);
  asg.seed(options.seed);
  asg.partition_ms(part.ms);
  asg.rejoin_timeout_s(options.rejoin_timeout_s);
  asg.replicas(options.replicas);
  asg.status_relay(options.status_relay);
  asg.replica_every(options.replica_every);
  asg.coarse_every(options.coarse_every);
  asg.coarse_aggregates(options.coarse_aggregates);
  asg.coarse_smoothing(options.coarse_smoothing);
  asg.refine(options.refine);
  asg.refine_grad_tol(options.refine_grad_tol);
  asg.refine_rel_tol(options.refine_rel_tol);
  asg.refine_sigma(options.refine_sigma);
  asg.setup_at_once(options.setup_at_once);
  if (options.robust.kind != RobustKind::kNone) {
    const RobustOptions& r = options.robust;
    asg.robust(robust_kind_name(r.kind));
    asg.inlier_threshold(r.inlier_threshold);
    asg.inlier_quantile(r.inlier_quantile);
    asg.gnc_max_outer(static_cast<std::uint32_t>(r.max_outer_iterations));
    asg.gnc_mu_step(r.mu_step);
    asg.gnc_inner_max_rounds(static_cast<std::uint32_t>(r.inner_max_rounds));
    asg.known_inliers(known_inliers_name(r.known_inliers));
    asg.gnc_known_start(options.gnc_known_start);
    asg.gnc_readmission_passes(static_cast<std::uint32_t>(r.readmission_passes));
    asg.gnc_recheck_probes(static_cast<std::uint32_t>(r.recheck_probes));
    asg.gnc_probe_ratio(r.probe_ratio);
    asg.gnc_final_refine(r.final_refine);
    asg.gnc_cluster_probes(options.gnc_cluster_probes);
    asg.gnc_pass_refine(r.refine_passes);
    asg.gnc_mu_step_max(r.mu_step_max);
    asg.known_inlier(structure.known_inlier);
  }
  return asg;
}

void publish_assignment(CoordinatorSession& session, wire::PartitionAssignment base, bool certify,
                        double timeout_s) {
  base.certify(certify);
  session.publish(base);
  std::string missing;
  expect_ready(session.ready_barrier(Seconds(timeout_s), &missing), session.mailroom(), timeout_s,
               "the agents to be ready", missing);
}

}  // namespace tessera::coordinator
