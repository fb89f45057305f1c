// A peer that "stopped responding" may be alive: when this process's own Fast DDS shared-memory
// listener is stuck on a message from a deleted participant (transport/fastdds/
// shm_receive_watch.hpp), every peer behind that port falls silent and is declared lost. The
// loss then names the stuck listener too, as a timed-out wait does, so the run's error says
// where the silence came from. No DDS domain: the tracker is fed as the discovery listener
// feeds it, and the receive error is queued as Fast DDS logs it.

#include <gtest/gtest.h>

#include <fastdds/dds/log/Log.hpp>
#include <string>

#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/inbox.hpp"
#include "transport/peer_tracking.hpp"

namespace tessera::transport {
namespace {

namespace dds = eprosima::fastdds::dds;

GuidPrefix prefix_of_byte(unsigned char b) {
  GuidPrefix p;
  p.value[0] = b;
  return p;
}

// Agent 1 of a two-agent run loses its coordinator (participant lease expired).
std::string reason_of_a_lost_coordinator() {
  Mailroom room;
  SessionOptions o;
  o.run_id = "loss-note";
  o.agent_id = 1;
  o.num_agents = 2;
  PeerTracker tracker(room, o, PeerIdentity{"loss-note", false, 1});
  tracker.set_loss_fatal(true);
  tracker.discovered(prefix_of_byte(7), PeerIdentity{"loss-note", true, 0});
  tracker.dropped(prefix_of_byte(7));
  return room.stopped() ? room.stop_info()->reason : "not stopped";
}

TEST(DdsPeerLossNote, ALossWhileThisProcessesListenerIsStuckNamesTheStuckListener) {
  watch_fastdds_log();
  dds::Log::Flush();
  if (shm_receive_failures() == 0) {
    const std::string plain = reason_of_a_lost_coordinator();
    EXPECT_NE(plain.find("it stopped responding (participant lease"), std::string::npos) << plain;
    EXPECT_EQ(plain.find("stuck"), std::string::npos) << plain;
  }
  dds::Log::QueueLog("Error receiving data: No such file or directory - 0x1 (0x2)",
                     dds::Log::Context{__FILE__, __LINE__, __func__, "RTPS_MSG_OUT"},
                     dds::Log::Kind::Warning);
  dds::Log::Flush();
  const std::string noted = reason_of_a_lost_coordinator();
  EXPECT_NE(noted.find("it stopped responding (participant lease"), std::string::npos) << noted;
  EXPECT_NE(noted.find("a listener of this process is stuck"), std::string::npos) << noted;
}

}  // namespace
}  // namespace tessera::transport
