#include "initialization_threads.hpp"

#include <gtest/gtest.h>

#include <exception>
#include <thread>

#include "thread_exchange.hpp"

namespace tessera::test {

std::vector<std::pair<std::uint32_t, std::uint32_t>> structure_of(const PoseGraph& g) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> s;
  for (const auto& m : g.measurements)
    s.emplace_back(static_cast<std::uint32_t>(m.i), static_cast<std::uint32_t>(m.j));
  return s;
}

std::vector<Pose> StageThreadsRun::poses() const {
  std::vector<Pose> all;
  for (const auto& r : results) all.insert(all.end(), r.poses.begin(), r.poses.end());
  return all;
}

StageThreadsRun run_initialization_threads(
    const PoseGraph& g, std::uint32_t N, const std::string& method, agent::EarlyChordal* early,
    const std::function<agent::SetupTurnOptions(std::uint32_t)>& turns_of) {
  ThreadExchange ex(N);
  StageThreadsRun run;
  for (std::uint32_t k = 0; k < N; ++k) run.shares.push_back(agent::robot_share(g, k, N));
  run.results.resize(N);
  std::vector<std::string> errors(N);
  const auto structure = structure_of(g);
  std::vector<std::thread> threads;
  for (std::uint32_t k = 0; k < N; ++k)
    threads.emplace_back([&, k] {
      ThreadChannel ch(ex, k);
      const agent::SetupTurnOptions turns = turns_of ? turns_of(k) : agent::SetupTurnOptions{};
      try {
        run.results[k] =
            agent::run_initialization_stage(run.shares[k], k, N, structure, method, "test", ch,
                                            20.0, k == 0 ? early : nullptr, turns);
      } catch (const std::exception& e) {
        errors[k] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  for (std::uint32_t k = 0; k < N; ++k) EXPECT_EQ(errors[k], "") << "agent " << k;
  run.left_over = ex.left_over();
  return run;
}

void expect_identical(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE(a[i].R == b[i].R) << "rotation of pose " << i;
    ASSERT_TRUE(a[i].t == b[i].t) << "translation of pose " << i;
  }
}

}  // namespace tessera::test
