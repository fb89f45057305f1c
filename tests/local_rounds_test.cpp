// Local rounds (local_rounds.hpp): after new data in one block of a converged iterate, only
// the blocks near it work and send; a block far from it sends nothing after the first status,
// the run still stops on the global gradient, and the delivery order does not change the
// iterates (the DDS agents run the same protocol).

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/distributed/local_rounds.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

constexpr int kRobots = 6;
constexpr int kPerRobot = 12;

Eigen::MatrixXd rotation(double angle) {
  Eigen::MatrixXd R(2, 2);
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return R;
}

// Robots along a line, robot r owning poses [12 r, 12 r + 12): odometry, intra-robot closures
// two poses apart, and two closures to the next robot only, so the blocks form a chain
// 0 - 1 - ... - 5. Measurements are the truth plus a fixed, deterministic disturbance.
PoseGraph chain_graph() {
  PoseGraph g;
  g.d = 2;
  g.num_poses = kRobots * kPerRobot;
  std::vector<Eigen::Vector2d> p(g.num_poses);
  std::vector<double> theta(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) {
    p[i] = Eigen::Vector2d(static_cast<double>(i), 0.3 * std::sin(0.5 * static_cast<double>(i)));
    theta[i] = 0.2 * std::cos(0.3 * static_cast<double>(i));
  }
  int k = 0;
  auto add = [&](std::size_t i, std::size_t j) {
    const double e = 0.02 * std::sin(1.7 * ++k);
    Measurement m;
    m.i = i;
    m.j = j;
    m.R = rotation(theta[j] - theta[i] + e);
    m.t = rotation(-theta[i]) * (p[j] - p[i]) + Eigen::Vector2d(e, -0.5 * e);
    m.kappa = 10.0;
    m.tau = 1.0;
    g.measurements.push_back(m);
  };
  for (int r = 0; r < kRobots; ++r) {
    const std::size_t first = static_cast<std::size_t>(r * kPerRobot);
    for (std::size_t s = 0; s + 1 < kPerRobot; ++s) add(first + s, first + s + 1);
    for (std::size_t s = 0; s + 2 < kPerRobot; s += 3) add(first + s, first + s + 2);
    if (r + 1 < kRobots) {
      add(first + kPerRobot - 1, first + kPerRobot);
      add(first + kPerRobot - 2, first + kPerRobot + 1);
    }
  }
  return g;
}

std::vector<int> robot_blocks() {
  std::vector<int> a(kRobots * kPerRobot);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<int>(i) / kPerRobot;
  return a;
}

// Forwards to an agent and counts what each of its messages is.
class Counting : public AgentProcess {
 public:
  explicit Counting(AgentProcess& inner) : inner_(inner) {}
  std::vector<OutgoingMessage> start() override { return count(inner_.start()); }
  std::vector<OutgoingMessage> handle(const ProtocolMessage& m) override {
    return count(inner_.handle(m));
  }
  bool done() const override { return inner_.done(); }
  std::size_t messages_needed() const override { return inner_.messages_needed(); }
  std::optional<AwaitedMessages> awaited() const override { return inner_.awaited(); }

  int statuses = 0;        // round statuses sent
  int later_statuses = 0;  // of them, after round 0
  int pose_blocks = 0;     // pose messages sent after the initial exchange

 private:
  std::vector<OutgoingMessage> count(std::vector<OutgoingMessage> out) {
    for (const auto& o : out) {
      if (const auto* s = std::get_if<RoundStatusMessage>(&o.message)) {
        ++statuses;
        if (s->round > 0) ++later_statuses;
      } else if (step_of_phase(std::get<PoseBlockMessage>(o.message).phase) !=
                 static_cast<std::uint32_t>(ProtocolPhase::kInit)) {
        ++pose_blocks;
      }
    }
    return out;
  }
  AgentProcess& inner_;
};

struct Outcome {
  Eigen::MatrixXd X;
  double cost = 0.0, grad_norm = 0.0;
  int rounds = 0;
  std::string stop_reason;
  std::vector<int> statuses, later_statuses, pose_blocks;
};

// The agents of `graph` (blocks = robots) from the lifted point X0, run in one process.
Outcome run(const PoseGraph& graph, const Eigen::MatrixXd& X0, const DistributedOptions& options,
            DeliveryOrder order = DeliveryOrder::kFifo) {
  const BlockLayout layout = make_block_layout(graph.num_poses, graph.measurements, robot_blocks());
  std::vector<std::unique_ptr<AgentState>> states;
  std::vector<std::unique_ptr<CertifiedAgent>> agents;
  std::vector<std::unique_ptr<Counting>> counters;
  std::vector<AgentProcess*> processes;
  for (int b = 0; b < layout.num_blocks; ++b) {
    states.push_back(std::make_unique<AgentState>(
        b, graph.d, layout, graph.measurements,
        gather_pose_columns(X0, layout.poses[static_cast<std::size_t>(b)], graph.d),
        options.algorithm_block_update()));
    agents.push_back(std::make_unique<CertifiedAgent>(*states.back(), layout, options));
    counters.push_back(std::make_unique<Counting>(*agents.back()));
    processes.push_back(counters.back().get());
  }
  run_in_process(processes, order, 7);
  Outcome out;
  out.X = Eigen::MatrixXd::Zero(X0.rows(), X0.cols());
  for (int b = 0; b < layout.num_blocks; ++b) {
    scatter_pose_columns(states[static_cast<std::size_t>(b)]->Y,
                         layout.poses[static_cast<std::size_t>(b)], graph.d, out.X);
    out.statuses.push_back(counters[static_cast<std::size_t>(b)]->statuses);
    out.later_statuses.push_back(counters[static_cast<std::size_t>(b)]->later_statuses);
    out.pose_blocks.push_back(counters[static_cast<std::size_t>(b)]->pose_blocks);
  }
  const auto& solve = agents.front()->solves().back();
  out.cost = solve.trace.back().cost;
  out.grad_norm = solve.trace.back().grad_norm;
  out.rounds = solve.rounds;
  out.stop_reason = solve.stop_reason;
  return out;
}

DistributedOptions options(bool local, double tol) {
  DistributedOptions o;
  o.rank = 3;
  o.grad_norm_tol = tol;
  o.round_result = false;
  o.local_rounds.enabled = local;
  o.refine.auto_interface_grad_tol = 0;  // the rounds to `tol` (no hand-over to the refinement)
  return o;
}

// The optimum of the chain graph (lifted), and the graph with one closure inside block 0 moved
// a little: new data in one block of a converged iterate.
struct Scenario {
  PoseGraph changed;
  Eigen::MatrixXd X;
};

Scenario scenario() {
  const PoseGraph g = chain_graph();
  const DistributedResult opt = solve_distributed(g, robot_blocks(), options(false, 1e-8));
  EXPECT_LE(opt.grad_norm, 1e-7);
  Scenario s{g, opt.X};
  for (Measurement& m : s.changed.measurements)
    if (m.i == 3 && m.j == 5) m.t(1) += 0.1;  // an intra-robot closure of robot 0
  return s;
}

TEST(LocalRounds, AfterNewDataInOneBlockABlockFarFromItSendsNothingAfterTheFirstStatus) {
  const Scenario s = scenario();
  const double tol = 1e-5;
  const Outcome local = run(s.changed, s.X, options(true, tol));
  const Outcome full = run(s.changed, s.X, options(false, tol));
  ASSERT_EQ(local.stop_reason, "grad_norm");
  ASSERT_EQ(full.stop_reason, "grad_norm");
  EXPECT_LE(local.grad_norm, tol);
  EXPECT_GE(local.rounds, 2);
  // Without local rounds every block sends its status in every round.
  for (int b = 0; b < kRobots; ++b) EXPECT_EQ(full.statuses[b], full.rounds + 1) << "block " << b;
  // With them, the last block (four blocks away from the change) sends its first status and
  // nothing else: no status, no poses.
  EXPECT_EQ(local.statuses[kRobots - 1], 1);
  EXPECT_EQ(local.later_statuses[kRobots - 1], 0);
  EXPECT_EQ(local.pose_blocks[kRobots - 1], 0);
  // The changed block works in both.
  EXPECT_GT(local.pose_blocks[0], 0);
  int sent_local = 0, sent_full = 0;
  for (int b = 0; b < kRobots; ++b) {
    sent_local += local.statuses[b] + local.pose_blocks[b];
    sent_full += full.statuses[b] + full.pose_blocks[b];
  }
  EXPECT_LT(sent_local, sent_full / 2);
  // Both end within the tolerance of the same optimum.
  EXPECT_NEAR(local.cost, full.cost, 1e-8 * full.cost);
  EXPECT_LT((local.X - full.X).norm(), 1e-4);
}

TEST(LocalRounds, TheDeliveryOrderDoesNotChangeTheIterates) {
  const Scenario s = scenario();
  const Outcome fifo = run(s.changed, s.X, options(true, 1e-5), DeliveryOrder::kFifo);
  const Outcome shuffled = run(s.changed, s.X, options(true, 1e-5), DeliveryOrder::kShuffled);
  const Outcome reversed = run(s.changed, s.X, options(true, 1e-5), DeliveryOrder::kReversed);
  EXPECT_EQ(fifo.rounds, shuffled.rounds);
  EXPECT_EQ((fifo.X - shuffled.X).norm(), 0.0);
  EXPECT_EQ((fifo.X - reversed.X).norm(), 0.0);
  EXPECT_EQ(fifo.statuses, shuffled.statuses);
}

TEST(LocalRounds, WithEveryBlockAboveTheBoundTheRoundsAreThePlainOnes) {
  // A threshold so low that no block ever rests: the same iterates as without local rounds.
  const Scenario s = scenario();
  DistributedOptions o = options(true, 1e-5);
  o.local_rounds.threshold = 1e-12;
  const Outcome local = run(s.changed, s.X, o);
  const Outcome full = run(s.changed, s.X, options(false, 1e-5));
  EXPECT_EQ(local.rounds, full.rounds);
  EXPECT_EQ((local.X - full.X).norm(), 0.0);
}

TEST(LocalRounds, RejectsBadOptionsNamingTheField) {
  LocalRoundOptions o;
  o.threshold = 0.0;
  EXPECT_THROW(o.validate(), InputError);
  o.threshold = 1.5;
  EXPECT_THROW(o.validate(), InputError);
  DistributedOptions d;
  d.local_rounds.enabled = true;
  d.coarse.enabled = true;
  EXPECT_TRUE(test::validation_names(d, "local_rounds"));
}

}  // namespace
}  // namespace tessera
