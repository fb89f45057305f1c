#include "thread_exchange.hpp"

#include <algorithm>
#include <chrono>

namespace tessera::test {

void ThreadExchange::post(std::uint32_t from, const OutgoingMessage& m) {
  std::lock_guard<std::mutex> lock(mu_);
  for (std::uint32_t a = 0; a < queues_.size(); ++a)
    if (a != from && (m.broadcast ||
                      std::find(m.recipients.begin(), m.recipients.end(), a) != m.recipients.end()))
      queues_[a].push_back(m.message);
  cv_.notify_all();
}

std::optional<ProtocolMessage> ThreadExchange::take(std::uint32_t self, double timeout_s) {
  std::unique_lock<std::mutex> lock(mu_);
  if (!cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                    [&] { return !queues_[self].empty(); }))
    return std::nullopt;
    // GCC 12 at -O2 reports the moved-from variant's scalars as maybe uninitialized (a known
    // false positive of -Wmaybe-uninitialized with std::variant); every field has an initializer.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  ProtocolMessage m = std::move(queues_[self].front());
  queues_[self].pop_front();
  return m;
#pragma GCC diagnostic pop
}

std::size_t ThreadExchange::left_over() {
  std::lock_guard<std::mutex> lock(mu_);
  std::size_t n = 0;
  for (const auto& q : queues_) n += q.size();
  return n;
}

}  // namespace tessera::test
