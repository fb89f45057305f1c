#include "coordinator/assignment_publishing.hpp"

#include <string>
#include <tessera/robust/robust_options.hpp>

#include "transport/assignment_options.hpp"
#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

namespace {

// What every agent runs, as the command line says (transport/assignment_options.hpp carries
// it).
agent::RunOptions agents_run_options(const CoordinatorOptions& o) {
  agent::RunOptions ro;
  ro.algorithm = o.algorithm;
  ro.initialization = o.init;
  ro.rank = o.rank;
  ro.max_rounds = o.max_rounds;
  ro.grad_norm_tolerance = o.grad_tol;
  ro.relative_cost_tolerance = o.rel_cost_tol;
  ro.seed = o.seed;
  ro.certify = false;  // publish_assignment sets it
  ro.coarse_every = o.coarse_every;
  ro.coarse_aggregates = o.coarse_aggregates;
  ro.coarse_smoothing = o.coarse_smoothing;
  ro.refine = o.refine;
  ro.refine_grad_tol = o.refine_grad_tol;
  ro.refine_rel_tol = o.refine_rel_tol;
  ro.refine_sigma = o.refine_sigma;
  ro.tangent_split_dots = o.tangent_split_dots;
  ro.robust = o.robust;
  ro.gnc_known_start = o.gnc_known_start;
  ro.gnc_cluster_probes = static_cast<int>(o.gnc_cluster_probes);
  return ro;
}

}  // namespace

wire::PartitionAssignment make_assignment(const CoordinatorOptions& options,
                                          const RunStructure& structure,
                                          const PartitionStepResult& part) {
  wire::PartitionAssignment asg;
  asg.run_id(options.net.session.run_id);
  asg.num_agents(options.agents);
  asg.num_poses(static_cast<std::uint32_t>(structure.num_poses));
  asg.dim(static_cast<std::uint32_t>(structure.d));
  asg.owner(part.owner);
  asg.edge_i(structure.edge_i);
  asg.edge_j(structure.edge_j);
  write_run_options(agents_run_options(options), asg);
  asg.partition_ms(part.ms);
  asg.rejoin_timeout_s(options.rejoin_timeout_s);
  asg.replicas(options.replicas);
  asg.status_relay(options.status_relay);
  asg.replica_every(options.replica_every);
  asg.setup_at_once(options.setup_at_once);
  if (options.robust.kind != RobustKind::kNone) asg.known_inlier(structure.known_inlier);
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
