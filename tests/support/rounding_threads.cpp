#include "rounding_threads.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <thread>

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

}  // namespace

Rounded round_in_threads(const RoundingCase& c, const DistributedRoundingOptions& options) {
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
    if (!errors[k].empty()) {
      r.errors.push_back("agent " + std::to_string(k) + ": " + errors[k]);
      continue;
    }
    for (std::size_t s = 0; s < layout.poses[k].size(); ++s)
      r.poses[layout.poses[k][s]] = out[k].poses[s];
    if (out[k].cost != out[0].cost ||
        out[k].translation_iterations != out[0].translation_iterations)
      r.errors.push_back("agent " + std::to_string(k) +
                         " ended with another cost or iteration count");
  }
  if (!r.errors.empty()) return r;
  r.cost = out[0].cost;
  r.iterations = out[0].translation_iterations;
  return r;
}

}  // namespace tessera::agent
