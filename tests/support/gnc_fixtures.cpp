#include "gnc_fixtures.hpp"

#include <tessera/robust/tls_weights.hpp>

namespace tessera::test {

GeneratorResult grid_with_outliers(double fraction, std::uint64_t seed) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 125;
  o.num_robots = 5;
  o.seed = seed;
  o.outlier_fraction = fraction;
  return generate_pose_graph(o);
}

GeneratorResult flexible_city(double fraction, OutlierKind kind, std::uint64_t seed) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kCity;
  o.num_poses = 300;
  o.num_robots = 5;
  o.seed = seed;
  o.outlier_fraction = fraction;
  o.outlier_kind = kind;
  GeneratorResult r = generate_pose_graph(o);
  for (Measurement& m : r.graph.measurements) {
    m.kappa *= 0.03;
    m.tau *= 0.03;
  }
  return r;
}

std::vector<int> robots_as_blocks(const GeneratorResult& r) {
  return std::vector<int>(r.robot_of.begin(), r.robot_of.end());
}

GncDistributedOptions irbcd_gnc() {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.algorithm = DistributedAlgorithm::kIrbcd;
  o.solver.grad_norm_tol = 1e-3;
  // The rounds schedule these tests state: GNC's solves and the passes by rounds, also where the
  // interface fits (RobustOptions::refine_passes; tests/gnc_refine_steps_test.cpp has it on).
  o.robust.refine_passes = false;
  // GNC's first weights after the plain solve's rounds, not at the voted start
  // (RobustOptions::weigh_at_start): the rough GNC these tests' schedules act on.
  o.robust.weigh_at_start = false;
  return o;
}

std::vector<bool> odometry_flags(const PoseGraph& g) {
  std::vector<bool> known(g.num_measurements());
  for (std::size_t e = 0; e < known.size(); ++e)
    known[e] = is_known_inlier(g.measurements[e], KnownInliers::kOdometry);
  return known;
}

}  // namespace tessera::test
