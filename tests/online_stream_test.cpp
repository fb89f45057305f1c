// The online stream model without DDS: batches absorbed into a growing graph, new poses
// initialised by composing measurements from the current estimate, and the agreement on when
// a batch enters a distributed run.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <tessera/online/absorb_gate.hpp>
#include <tessera/online/estimate_extension.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/new_pose_placement.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {

Pose planar(double x, double y, double theta) {
  Pose p = Pose::identity(2);
  p.R = Eigen::Rotation2Dd(theta).toRotationMatrix();
  p.t << x, y;
  return p;
}

StreamMeasurement link(PoseKey from, PoseKey to, const Pose& relative, MeasurementKind kind) {
  StreamMeasurement m;
  m.from = from;
  m.to = to;
  m.kind = kind;
  m.relative = relative;
  return m;
}

StreamBatch batch(std::uint32_t robot, std::uint64_t sequence, std::vector<StreamPose> poses,
                  std::vector<StreamMeasurement> measurements = {}) {
  StreamBatch b;
  b.robot = robot;
  b.sequence = sequence;
  b.poses = std::move(poses);
  b.measurements = std::move(measurements);
  return b;
}

StreamPose pose(std::uint32_t robot, std::uint64_t index) {
  return StreamPose{{robot, index}, 0.0, Pose::identity(2)};
}

TEST(GraphStream, AppendsPosesInArrivalOrderAndKeepsRobotKeys) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  s.absorb(batch(1, 0, {pose(1, 0)}));
  const auto g = s.absorb(batch(
      0, 1, {pose(0, 1)}, {link({0, 0}, {0, 1}, planar(1, 0, 0), MeasurementKind::kOdometry)}));
  EXPECT_EQ(g.first_new_pose, 2u);
  EXPECT_EQ(g.num_new_poses, 1u);
  EXPECT_EQ(g.num_new_measurements, 1u);
  ASSERT_EQ(s.graph().num_poses, 3u);
  EXPECT_EQ(s.id_of({1, 0}), std::optional<std::size_t>(1));
  EXPECT_EQ(s.graph().measurements[0].i, 0u);
  EXPECT_EQ(s.graph().measurements[0].j, 2u);
  EXPECT_EQ(s.robots(), (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(s.absorbed_batches(0), 2u);
}

TEST(GraphStream, WaitsForAMissingBatchOfTheSameRobot) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  const auto early = s.absorb(batch(0, 2, {pose(0, 2)}));
  EXPECT_TRUE(early.empty());
  EXPECT_EQ(s.queued_batches(), 1u);
  const auto both = s.absorb(batch(0, 1, {pose(0, 1)}));
  EXPECT_EQ(both.batches, 2u);
  EXPECT_EQ(both.num_new_poses, 2u);
  EXPECT_EQ(s.key_of_pose()[2].index, 2u);
}

TEST(GraphStream, HoldsAClosureUntilTheOtherRobotsPoseArrives) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)},
                 {link({0, 0}, {1, 0}, planar(0, 1, 0), MeasurementKind::kInterLoop)}));
  EXPECT_EQ(s.graph().measurements.size(), 0u);
  EXPECT_EQ(s.held_measurements(), 1u);
  s.absorb(batch(1, 0, {pose(1, 0)}));
  EXPECT_EQ(s.held_measurements(), 0u);
  ASSERT_EQ(s.graph().measurements.size(), 1u);
  EXPECT_EQ(s.kinds()[0], MeasurementKind::kInterLoop);
}

TEST(GraphStream, RejectsWhatCannotBeRightNamingRobotAndBatch) {
  GraphStream s(2, "topic X");
  s.absorb(batch(0, 0, {pose(0, 0)}));
  auto message = [&](const StreamBatch& b) {
    try {
      s.absorb(b);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(batch(0, 0, {pose(0, 5)})).find("topic X: robot 0 batch 0: received twice"),
            std::string::npos);
  EXPECT_NE(message(batch(0, 1, {pose(0, 0)})).find("not after the robot's previous pose"),
            std::string::npos);
  EXPECT_NE(message(batch(1, 0, {pose(2, 0)})).find("belongs to another robot"), std::string::npos);
  StreamPose bad = pose(3, 0);
  bad.guess.R(0, 0) = 2.0;
  EXPECT_NE(message(batch(3, 0, {bad})).find("not a 2D pose"), std::string::npos);
  auto self = link({0, 0}, {0, 0}, planar(0, 0, 0), MeasurementKind::kIntraLoop);
  EXPECT_NE(message(batch(4, 0, {}, {self})).find("joins a pose to itself"), std::string::npos);
  auto weightless = link({0, 0}, {4, 0}, planar(0, 0, 0), MeasurementKind::kInterLoop);
  weightless.tau = 0;
  EXPECT_NE(message(batch(5, 0, {}, {weightless})).find("kappa and tau"), std::string::npos);
  // A rejected batch changes nothing.
  EXPECT_EQ(s.graph().num_poses, 1u);
  EXPECT_EQ(s.graph().measurements.size(), 0u);
}

TEST(EstimateExtension, ComposesNewPosesAlongOdometryFromTheLiftedEstimate) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  // A lifted estimate of pose 0 that is not [I; 0]: a rotation inside R^{4 x 2}.
  Eigen::MatrixXd X = lift_poses({planar(2, -1, 0.3)}, 4);
  const Eigen::MatrixXd Q = Eigen::MatrixXd::Random(4, 4).householderQr().householderQ();
  X = Q * X;
  s.absorb(batch(0, 1, {pose(0, 1), pose(0, 2)},
                 {link({0, 0}, {0, 1}, planar(1, 0, 0.5), MeasurementKind::kOdometry),
                  // Written backwards: pose 2 is the measurement's i.
                  link({0, 2}, {0, 1}, planar(0, 2, -0.2), MeasurementKind::kOdometry)}));
  const EstimateExtension ext = extend_estimate(s.graph(), X, s.guesses());
  EXPECT_EQ(ext.composed, 2u);
  EXPECT_EQ(ext.from_guess, 0u);
  auto Y = [&](int k) { return Eigen::MatrixXd(ext.X.middleCols(3 * k, 2)); };
  auto p = [&](int k) { return Eigen::VectorXd(ext.X.col(3 * k + 2)); };
  // Every measurement is satisfied exactly: Y_j = Y_i R_ij and p_j = p_i + Y_i t_ij.
  for (const Measurement& m : s.graph().measurements) {
    const int i = static_cast<int>(m.i), j = static_cast<int>(m.j);
    EXPECT_LT((Y(j) - Y(i) * m.R).norm(), 1e-12);
    EXPECT_LT((p(j) - p(i) - Y(i) * m.t).norm(), 1e-12);
  }
  // The new poses stay on the Stiefel manifold.
  for (int k = 1; k < 3; ++k)
    EXPECT_LT((Y(k).transpose() * Y(k) - Eigen::MatrixXd::Identity(2, 2)).norm(), 1e-12);
}

TEST(EstimateExtension, StartsAnUnlinkedRobotFromItsGuessAndComposesTheRest) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  StreamPose first{{1, 0}, 0.0, planar(5, 5, 1.0)};
  s.absorb(batch(1, 0, {first, pose(1, 1)},
                 {link({1, 0}, {1, 1}, planar(1, 0, 0), MeasurementKind::kOdometry)}));
  const EstimateExtension ext =
      extend_estimate(s.graph(), lift_poses({planar(0, 0, 0)}, 3), s.guesses());
  EXPECT_EQ(ext.from_guess, 1u);
  EXPECT_EQ(ext.composed, 1u);
  EXPECT_LT((ext.X.block(0, 3, 2, 2) - first.guess.R).norm(), 1e-12);
  EXPECT_LT((ext.X.block(0, 5, 2, 1) - first.guess.t).norm(), 1e-12);
  EXPECT_EQ(ext.X.block(2, 3, 1, 3).norm(), 0.0);  // the lifted extra row stays zero
  Eigen::Vector2d expected = first.guess.t + first.guess.R * Eigen::Vector2d(1, 0);
  EXPECT_LT((ext.X.block(0, 8, 2, 1) - expected).norm(), 1e-12);
}

// The lifted objective sum kappa ||Y_j - Y_i R_ij||^2 + tau ||p_j - p_i - Y_i t_ij||^2.
double lifted_cost(const PoseGraph& g, const Eigen::MatrixXd& X) {
  const int d = g.d, w = d + 1;
  double f = 0.0;
  for (const Measurement& m : g.measurements) {
    const auto Yi = X.middleCols(w * static_cast<Eigen::Index>(m.i), d);
    const auto Yj = X.middleCols(w * static_cast<Eigen::Index>(m.j), d);
    const auto pi = X.col(w * static_cast<Eigen::Index>(m.i) + d);
    const auto pj = X.col(w * static_cast<Eigen::Index>(m.j) + d);
    f += m.kappa * (Yj - Yi * m.R).squaredNorm() + m.tau * (pj - pi - Yi * m.t).squaredNorm();
  }
  return f;
}

// Pose 0 estimated; a new chain 1, 2, 3 whose odometry turns a little too far, and a closure
// from 3 back to 0 that disagrees with the composed chain.
GraphStream loop_of_new_poses() {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  s.absorb(batch(0, 1, {pose(0, 1), pose(0, 2), pose(0, 3)},
                 {link({0, 0}, {0, 1}, planar(1, 0, 1.65), MeasurementKind::kOdometry),
                  link({0, 1}, {0, 2}, planar(1, 0, 1.65), MeasurementKind::kOdometry),
                  link({0, 2}, {0, 3}, planar(1, 0, 1.65), MeasurementKind::kOdometry),
                  link({0, 3}, {0, 0}, planar(1, 0, 1.5708), MeasurementKind::kIntraLoop)}));
  return s;
}

TEST(NewPosePlacement, ALoopClosureOfNewPosesLowersTheCostOfTheComposedStart) {
  const GraphStream s = loop_of_new_poses();
  Eigen::MatrixXd X0 = lift_poses({planar(2, -1, 0.3)}, 3);
  const Eigen::MatrixXd Q = Eigen::MatrixXd::Random(3, 3).householderQr().householderQ();
  X0 = Q * X0;
  Eigen::MatrixXd X = extend_estimate(s.graph(), X0, s.guesses()).X;
  const double composed = lifted_cost(s.graph(), X);
  const NewPosePlacement placed = place_new_poses(s.graph(), X, 1, 0);
  EXPECT_EQ(placed.placed, 3u);
  EXPECT_EQ(placed.measurements, 4u);
  const double after = lifted_cost(s.graph(), X);
  EXPECT_GT(composed, 0.05);  // the closure disagrees with the chain by 0.24 rad
  EXPECT_LT(after, 0.5 * composed);
  // The estimated pose does not move and the new ones stay on the Stiefel manifold.
  EXPECT_EQ(X.leftCols(3), X0);
  for (int k = 1; k < 4; ++k) {
    const Eigen::MatrixXd Y = X.middleCols(3 * k, 2);
    EXPECT_LT((Y.transpose() * Y - Eigen::MatrixXd::Identity(2, 2)).norm(), 1e-12);
  }
}

TEST(NewPosePlacement, LeavesNewPosesThatOnlyExtendOdometryAsComposed) {
  GraphStream s(2);
  s.absorb(batch(0, 0, {pose(0, 0)}));
  s.absorb(batch(0, 1, {pose(0, 1), pose(0, 2)},
                 {link({0, 0}, {0, 1}, planar(1, 0, 0.5), MeasurementKind::kOdometry),
                  link({0, 1}, {0, 2}, planar(1, 0, 0.5), MeasurementKind::kOdometry)}));
  Eigen::MatrixXd X = extend_estimate(s.graph(), lift_poses({planar(0, 0, 0)}, 3), s.guesses()).X;
  const Eigen::MatrixXd composed = X;
  EXPECT_EQ(place_new_poses(s.graph(), X, 1, 0).placed, 0u);
  EXPECT_EQ(X, composed);
}

TEST(AbsorbGate, ANewCutMeasurementEntersBothAgentsOnTheSameRound) {
  // Robot 1 publishes an inter-robot closure in its batch 3. Agent 0 receives it in round 5,
  // agent 1 (the publisher's agent) in round 4. Each agent runs its own gate on the statuses
  // of all agents (which all of them receive), so both let the batch in after the first
  // round whose statuses show it at BOTH agents.
  std::vector<Watermarks> held = {{{1, 3}}, {{1, 3}}};  // batches 0..2 held by both
  AbsorbGate gate_of_agent[2];
  int entered_round[2] = {-1, -1};
  for (int round = 0; round < 8; ++round) {
    if (round == 4) held[1][1] = 4;
    if (round == 5) held[0][1] = 4;
    // Round statuses are broadcast: every agent sees the same reports, in any order.
    std::vector<Watermarks> seen_by_0 = {held[0], held[1]};
    std::vector<Watermarks> seen_by_1 = {held[1], held[0]};
    if (gate_of_agent[0].decide(seen_by_0).at(1) == 4 && entered_round[0] < 0)
      entered_round[0] = round + 1;
    if (gate_of_agent[1].decide(seen_by_1).at(1) == 4 && entered_round[1] < 0)
      entered_round[1] = round + 1;
  }
  EXPECT_EQ(entered_round[0], 6);
  EXPECT_EQ(entered_round[1], 6);
}

TEST(AbsorbGate, NeverTakesDataOutAgainAndCountsAMissingRobotAsNone) {
  AbsorbGate gate;
  EXPECT_EQ(gate.decide({{{0, 2}, {1, 1}}, {{0, 3}}}).at(0), 2u);
  EXPECT_EQ(gate.entered(1), 0u);     // agent 1 has none of robot 1's batches yet
  gate.decide({{{0, 1}}, {{0, 1}}});  // a restarted agent reports less
  EXPECT_EQ(gate.entered(0), 2u);
}

}  // namespace
}  // namespace tessera
