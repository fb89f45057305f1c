// The count behind the note that a timed-out wait appends when a Fast DDS 2.9 shared-memory
// listener is stuck on a message from a deleted participant
// (transport/fastdds/shm_receive_watch.hpp). No DDS domain: the entries are queued here as
// Fast DDS queues them (category, kind and text as its SHM channel logs them).

#include "transport/fastdds/shm_receive_watch.hpp"

#include <gtest/gtest.h>

#include <fastdds/dds/log/Log.hpp>
#include <string>

namespace tessera::transport {
namespace {

namespace dds = eprosima::fastdds::dds;

void queue_warning(const char* category, const std::string& message) {
  dds::Log::QueueLog(message, dds::Log::Context{__FILE__, __LINE__, __func__, category},
                     dds::Log::Kind::Warning);
}

TEST(ShmReceiveWatch, CountsTheStuckListenersReceiveErrorsAndNothingElse) {
  watch_fastdds_log();
  const std::uint64_t before = shm_receive_failures();
  queue_warning("RTPS_EDP", "INCOMPATIBLE QOS (topic: tessera_control): Different Partitions");
  queue_warning("RTPS_TRANSPORT_SHM", "SHM Port 36913 failure: the port is marked as not ok!");
  for (int i = 0; i < 3; ++i)
    queue_warning("RTPS_MSG_OUT",
                  "Error receiving data: No such file or directory - 0x563796c1c7e0 "
                  "(0x563796c1c8a0)");
  dds::Log::Flush();
  EXPECT_EQ(shm_receive_failures() - before, 3u);
}

TEST(ShmReceiveWatch, TheNoteIsEmptyWithoutSuchErrorsAndNamesTheDefectAndTheCountWithThem) {
  watch_fastdds_log();
  dds::Log::Flush();
  if (shm_receive_failures() == 0) {
    EXPECT_EQ(shm_receive_note(), "");
  }
  queue_warning("RTPS_MSG_OUT", "Error receiving data: No such file or directory - 0x1 (0x2)");
  dds::Log::Flush();
  const std::string note = shm_receive_note();
  EXPECT_NE(note.find(std::to_string(shm_receive_failures()) + " receive errors"),
            std::string::npos)
      << note;
  EXPECT_NE(note.find("Fast DDS 2.9 defect"), std::string::npos) << note;
  EXPECT_NE(note.find("shm_receive_watch.hpp"), std::string::npos) << note;
}

}  // namespace
}  // namespace tessera::transport
