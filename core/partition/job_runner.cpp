#include "partition/job_runner.hpp"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>

namespace tessera::partition_detail {

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

std::vector<double> run_jobs(const std::vector<std::function<void()>>& jobs, int workers) {
  std::vector<std::exception_ptr> errors(jobs.size());
  std::atomic<std::size_t> next{0};
  const int count = std::max(1, std::min(workers, static_cast<int>(jobs.size())));
  std::vector<double> cpu(static_cast<std::size_t>(count), 0.0);
  auto work = [&](int t) {
    const double c0 = thread_cpu_ms();
    for (std::size_t j = next++; j < jobs.size(); j = next++) {
      try {
        jobs[j]();
      } catch (...) {
        errors[j] = std::current_exception();
      }
    }
    cpu[static_cast<std::size_t>(t)] = thread_cpu_ms() - c0;
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < count; ++t) threads.emplace_back(work, t);
  work(0);
  for (auto& t : threads) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
  return cpu;
}

}  // namespace tessera::partition_detail
