#pragma once
// The Fast DDS listeners of a session: they run on Fast DDS's threads and only translate
// events into calls on the session's trackers (participant discovery and removal -> peer
// tracking, endpoint (un)matches -> readiness, writer liveliness lost -> peer tracking,
// samples available -> the reader's drain function). Internal to transport/.

#include <atomic>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <functional>
#include <memory>
#include <string>

#include "transport/dds_trace.hpp"
#include "transport/inbox.hpp"
#include "transport/peer_tracking.hpp"
#include "transport/readiness.hpp"

namespace tessera::transport {

/// Set when the participant a listener belongs to is being replaced (DdsEntities::retire):
/// from then on its listeners ignore every event, so only the new participant's count.
using MuteFlag = std::shared_ptr<const std::atomic<bool>>;

/// Participants appearing, leaving or dropped (lease expired) on the domain: traced, then
/// those of this run (by participant name, with the tags of their USER_DATA) are reported to
/// the PeerTracker. With DDS Security, completed handshakes are reported too.
class ParticipantDiscoveryListener : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  ParticipantDiscoveryListener(PeerTracker& peers, const std::string& run_id, Mailroom& room,
                               const DdsTrace& trace, MuteFlag muted);
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;
#if HAVE_SECURITY
  // With DDS Security a peer's endpoints match only after this.
  void onParticipantAuthentication(
      eprosima::fastdds::dds::DomainParticipant*,
      eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override;
#endif

 private:
  PeerTracker& peers_;
  std::string run_id_;
  Mailroom& room_;
  const DdsTrace& trace_;
  MuteFlag muted_;
};

/// A writer's matches and unmatches, reported to Readiness as endpoint `name` ("<topic>/w").
class WriterMatchListener : public eprosima::fastdds::dds::DataWriterListener {
 public:
  WriterMatchListener(Readiness& readiness, std::string name, MuteFlag muted);
  void on_publication_matched(eprosima::fastdds::dds::DataWriter*,
                              const eprosima::fastdds::dds::PublicationMatchedStatus& st) override;

 private:
  Readiness& readiness_;
  std::string name_;
  MuteFlag muted_;
};

/// A reader's samples (handed to `drain`), matches (to Readiness as endpoint `name`,
/// "<topic>/r") and lost writer liveliness (to the PeerTracker).
class ReaderListener : public eprosima::fastdds::dds::DataReaderListener {
 public:
  ReaderListener(Readiness& readiness, PeerTracker& peers, std::string name,
                 std::function<void(eprosima::fastdds::dds::DataReader*)> drain, MuteFlag muted);
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader*,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& st) override;
  void on_liveliness_changed(eprosima::fastdds::dds::DataReader*,
                             const eprosima::fastdds::dds::LivelinessChangedStatus& st) override;

 private:
  Readiness& readiness_;
  PeerTracker& peers_;
  std::string name_;
  std::function<void(eprosima::fastdds::dds::DataReader*)> drain_;
  MuteFlag muted_;
};

/// The participant (GUID prefix) of an endpoint handle reported by a listener.
GuidPrefix prefix_of(const eprosima::fastrtps::rtps::InstanceHandle_t& handle);

}  // namespace tessera::transport
