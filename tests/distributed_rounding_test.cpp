// The agents' distributed rounding (core/runtime/distributed_rounding.hpp) in process: one thread
// per agent over an in-memory channel, no DDS. Against core's round_solution (the direct
// translation solve) on iterates of the in-process distributed solver:
//  - from zero with only the residual stop it is the direct solve (positions to 1e-9);
//  - started from the iterate's translations with the cost stop (the defaults), the rounded
//    cost is within the documented bound of the direct solve's (cost_bound() * max(1, f(X))
//    above it, never below it by more than rounding error), in fewer CG iterations.

#include "runtime/distributed_rounding.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <mutex>
#include <string>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/util/input_error.hpp>
#include <thread>
#include <vector>

#include "runtime/round_mailbox.hpp"

namespace tessera::agent {
namespace {

// N queues; send() copies a message into its recipients' queues (never back to the sender).
class Exchange {
 public:
  explicit Exchange(std::uint32_t n) : queues_(n) {}
  void post(std::uint32_t from, const OutgoingMessage& m) {
    std::lock_guard<std::mutex> lock(mu_);
    for (std::uint32_t a = 0; a < queues_.size(); ++a)
      if (a != from && (m.broadcast || std::find(m.recipients.begin(), m.recipients.end(), a) !=
                                           m.recipients.end()))
        queues_[a].push_back(m.message);
    cv_.notify_all();
  }
  std::optional<ProtocolMessage> take(std::uint32_t self, double timeout_s) {
    std::unique_lock<std::mutex> lock(mu_);
    if (!cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                      [&] { return !queues_[self].empty(); }))
      return std::nullopt;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    ProtocolMessage m = std::move(queues_[self].front());
#pragma GCC diagnostic pop
    queues_[self].pop_front();
    return m;
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<std::deque<ProtocolMessage>> queues_;
};

class ThreadChannel : public ProtocolChannel {
 public:
  ThreadChannel(Exchange& ex, std::uint32_t self) : ex_(ex), self_(self) {}
  void send(const OutgoingMessage& m) override { ex_.post(self_, m); }
  std::optional<ProtocolMessage> receive(double timeout_s) override {
    return ex_.take(self_, timeout_s);
  }

 private:
  Exchange& ex_;
  std::uint32_t self_;
};

struct Rounded {
  std::vector<Pose> poses;  // global order
  double cost = 0;          // as the agents summed it
  std::uint32_t iterations = 0;
};

// A generated 3D grid, its poses split into N contiguous blocks, and the in-process solver's
// lifted iterate after `max_rounds` rounds (a point near, not at, a critical point, as the
// runs the rounding follows usually stop).
struct Case {
  PoseGraph graph;
  std::vector<int> assignment;
  DistributedResult solved;
};

Case make_case(std::size_t poses, int agents, int max_rounds) {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kGrid3d;
  g.num_poses = poses;
  g.num_robots = static_cast<std::size_t>(agents);
  g.seed = 3;
  Case c;
  c.graph = generate_pose_graph(g).graph;
  for (std::size_t i = 0; i < c.graph.num_poses; ++i)
    c.assignment.push_back(
        static_cast<int>(i * static_cast<std::size_t>(agents) / c.graph.num_poses));
  DistributedOptions o;
  o.max_rounds = max_rounds;
  c.solved = solve_distributed(c.graph, c.assignment, o, c.graph.initial);
  return c;
}

Rounded round_in_threads(const Case& c, const DistributedRoundingOptions& options) {
  const PoseGraph& g = c.graph;
  const auto N =
      static_cast<std::uint32_t>(*std::max_element(c.assignment.begin(), c.assignment.end()) + 1);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, c.assignment);
  const int d = g.d;
  Exchange ex(N);
  std::vector<RoundLoopResult> out(N);
  std::vector<std::string> errors(N);
  std::vector<std::thread> threads;
  for (std::uint32_t k = 0; k < N; ++k)
    threads.emplace_back([&, k] {
      try {
        AgentLocalData local;
        local.agent_id = k;
        local.num_agents = N;
        local.d = d;
        local.num_poses = g.num_poses;
        for (int b : c.assignment) local.owner.push_back(static_cast<std::uint32_t>(b));
        local.owned = std::vector<std::uint32_t>(layout.poses[k].begin(), layout.poses[k].end());
        for (const Measurement& m : g.measurements)
          if (local.owner[m.i] == k || local.owner[m.j] == k) local.measurements.push_back(m);
        Eigen::MatrixXd Y(c.solved.X.rows(),
                          (d + 1) * static_cast<Eigen::Index>(local.owned.size()));
        for (std::size_t s = 0; s < local.owned.size(); ++s)
          Y.middleCols((d + 1) * static_cast<Eigen::Index>(s), d + 1) =
              c.solved.X.middleCols((d + 1) * static_cast<Eigen::Index>(local.owned[s]), d + 1);
        const AgentState state(static_cast<int>(k), d, layout, local.measurements, Y);
        ThreadChannel ch(ex, k);
        Mailbox mail(ch, 30.0, k);
        mail.set_num_agents(N);
        RoundLoopResult res;
        res.relaxation_cost = c.solved.relaxation_cost;
        out[k] = DistributedRounding(local, layout, state, mail, options).run(res);
      } catch (const std::exception& e) {
        errors[k] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  Rounded r;
  r.poses.resize(g.num_poses);
  for (std::uint32_t k = 0; k < N; ++k) {
    EXPECT_EQ(errors[k], "") << "agent " << k;
    if (!errors[k].empty()) continue;
    for (std::size_t s = 0; s < layout.poses[k].size(); ++s)
      r.poses[layout.poses[k][s]] = out[k].poses[s];
    EXPECT_EQ(out[k].cost, out[0].cost) << "every agent sums the same cost";
    EXPECT_EQ(out[k].translation_iterations, out[0].translation_iterations);
  }
  r.cost = out[0].cost;
  r.iterations = out[0].translation_iterations;
  return r;
}

// Pose k's position in pose 0's frame: free of the rotation frame a rounding picks.
Eigen::VectorXd in_frame_of_pose_0(const std::vector<Pose>& p, std::size_t k) {
  return p[0].R.transpose() * (p[k].t - p[0].t);
}

double worst_position_gap(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  double worst = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    worst = std::max(worst, (in_frame_of_pose_0(a, k) - in_frame_of_pose_0(b, k)).norm());
  return worst;
}

TEST(DistributedRounding, FromZeroToTheResidualStopItIsTheDirectSolve) {
  const Case c = make_case(1000, 4, 20);
  DistributedRoundingOptions exact;
  exact.warm_start = false;
  exact.settle_tolerance = 0;
  const Rounded r = round_in_threads(c, exact);
  EXPECT_LT(worst_position_gap(r.poses, c.solved.poses), 1e-9);
  EXPECT_NEAR(r.cost, c.solved.cost, 1e-12 * c.solved.cost);
}

TEST(DistributedRounding, WarmStartAndCostStopStayWithinTheBoundInFewerIterations) {
  for (int rounds : {20, 200}) {
    const Case c = make_case(1000, 4, rounds);
    DistributedRoundingOptions exact;
    exact.warm_start = false;
    exact.settle_tolerance = 0;
    const Rounded cold = round_in_threads(c, exact);
    const DistributedRoundingOptions defaults;
    const Rounded warm = round_in_threads(c, defaults);
    // The direct solve's translations minimise the cost for the rounded rotations: the
    // inexact solve can only be above it, by at most the documented bound (cost_bound()).
    const double f_direct = evaluate_objective(c.graph, c.solved.poses);
    const double bound = defaults.cost_bound() * std::max(1.0, c.solved.relaxation_cost);
    EXPECT_LE(warm.cost - f_direct, bound) << "after " << rounds << " rounds";
    EXPECT_GE(warm.cost - f_direct, -1e-12 * f_direct) << "after " << rounds << " rounds";
    EXPECT_LE(evaluate_objective(c.graph, warm.poses) - f_direct, bound);
    // Starting from the iterate's translations and stopping when the cost is settled takes
    // fewer all-agent steps than the exact solve from zero.
    EXPECT_LT(warm.iterations, cold.iterations) << "after " << rounds << " rounds";
    std::printf(
        "after %d rounds: %u CG iterations from zero to 1e-12, %u warm to the cost "
        "bound; cost above the direct solve's %.3g (bound %.3g)\n",
        rounds, cold.iterations, warm.iterations, warm.cost - f_direct, bound);
  }
}

// Not a test: the figures of scripts/bench/rounding_iterations.py (run with
// --gtest_also_run_disabled_tests). On each shared paper graph, 5 contiguous blocks, the
// in-process solver to its default tolerance (0.01) and to 30 rounds, then the rounding from
// zero to the residual stop (the algorithm before the warm start) and with the defaults; one
// line "ROUNDING graph rounds cold warm excess bound" each.
TEST(DistributedRounding, DISABLED_IterationsOnThePaperGraphs) {
  for (const char* name : {"intel", "CSAIL", "sphere2500", "torus3D", "parking-garage", "cubicle",
                           "manhattan3500", "city10000", "kitti_00"}) {
    const std::string path = std::string(TESSERA_SHARED_DIR) + "/datasets/" + name + ".g2o";
    if (!std::ifstream(path)) continue;
    for (int rounds : {30, 10000}) {
      Case c;
      c.graph = read_g2o(path);
      for (std::size_t i = 0; i < c.graph.num_poses; ++i)
        c.assignment.push_back(static_cast<int>(i * 5 / c.graph.num_poses));
      DistributedOptions o;
      o.max_rounds = rounds;
      c.solved = solve_distributed(c.graph, c.assignment, o);
      DistributedRoundingOptions exact;
      exact.warm_start = false;
      exact.settle_tolerance = 0;
      const Rounded cold = round_in_threads(c, exact);
      const DistributedRoundingOptions defaults;
      const Rounded warm = round_in_threads(c, defaults);
      std::printf("ROUNDING %s %d %u %u %.3e %.3e\n", name, c.solved.rounds, cold.iterations,
                  warm.iterations, warm.cost - cold.cost,
                  defaults.settle_tolerance * std::max(1.0, c.solved.relaxation_cost));
    }
  }
}

TEST(DistributedRounding, OptionsOutOfRangeNameTheField) {
  DistributedRoundingOptions o;
  o.settle_tolerance = -1;
  EXPECT_THROW(
      {
        try {
          o.validate();
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("settle_tolerance"), std::string::npos);
          throw;
        }
      },
      InputError);
  o = {};
  o.settle_window = 0;
  EXPECT_THROW(o.validate(), InputError);
}

}  // namespace
}  // namespace tessera::agent
