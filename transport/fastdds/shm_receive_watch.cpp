#include "transport/fastdds/shm_receive_watch.hpp"

#include <atomic>
#include <cstdlib>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutConsumer.hpp>
#include <memory>
#include <mutex>

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;

namespace {

std::atomic<std::uint64_t> failures{0};

// Counts the stuck listener's receive errors; passes entries on to Fast DDS's default consumer
// (errors always, warnings with TESSERA_DDS_LOG=1).
class CountingConsumer : public dds::LogConsumer {
 public:
  explicit CountingConsumer(bool show_warnings) : show_warnings_(show_warnings) {}
  void Consume(const dds::Log::Entry& entry) override {
    if (entry.kind == dds::Log::Kind::Warning &&
        entry.message.rfind("Error receiving data: No such file or directory", 0) == 0)
      failures.fetch_add(1, std::memory_order_relaxed);
    if (entry.kind == dds::Log::Kind::Error || show_warnings_) print_.Consume(entry);
  }

 private:
  bool show_warnings_;
  dds::StdoutConsumer print_;  // Fast DDS 2.9's default consumer
};

}  // namespace

void watch_fastdds_log() {
  static std::once_flag once;
  std::call_once(once, [] {
    const char* env = std::getenv("TESSERA_DDS_LOG");
    const bool show = env && *env && *env != '0';
    dds::Log::ClearConsumers();
    dds::Log::RegisterConsumer(std::make_unique<CountingConsumer>(show));
    dds::Log::SetVerbosity(dds::Log::Kind::Warning);
  });
}

std::uint64_t shm_receive_failures() {
  return failures.load(std::memory_order_relaxed);
}

std::string shm_receive_note() {
  const std::uint64_t n = shm_receive_failures();
  if (n == 0) return "";
  return "Fast DDS shared memory: a listener of this process is stuck on a message from a "
         "participant deleted before it was read (" +
         std::to_string(n) +
         " receive errors 'No such file or directory', a Fast DDS 2.9 defect: "
         "transport/fastdds/shm_receive_watch.hpp); this process receives nothing more on "
         "that port";
}

}  // namespace tessera::transport
