#include "transport/dds_listeners.hpp"

#include <fastdds/rtps/common/InstanceHandle.h>

#include <sstream>

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

GuidPrefix prefix_of(const rtps::InstanceHandle_t& handle) {
  return rtps::iHandle2GUID(handle).guidPrefix;
}

ParticipantDiscoveryListener::ParticipantDiscoveryListener(PeerTracker& peers,
                                                           const std::string& run_id,
                                                           Mailroom& room, const DdsTrace& trace,
                                                           MuteFlag muted)
    : peers_(peers), run_id_(run_id), room_(room), trace_(trace), muted_(std::move(muted)) {}

void ParticipantDiscoveryListener::on_participant_discovery(dds::DomainParticipant*,
                                                            rtps::ParticipantDiscoveryInfo&& info) {
  if (*muted_) return;
  const auto status = info.status;
  const GuidPrefix& prefix = info.info.m_guid.guidPrefix;
  const std::string name = info.info.m_participantName.to_string();
  if (peers_.is_own(prefix)) return;
  if (trace_.on()) {
    std::ostringstream os;
    os << prefix;
    trace_("participant %s: '%s' %s",
           status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT    ? "discovered"
           : status == rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT     ? "removed"
           : status == rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT     ? "dropped"
           : status == rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT ? "changed"
                                                                               : "ignored",
           name.c_str(), os.str().c_str());
  }
  auto who = parse_participant_name(name);
  if (!who || who->run_id != run_id_) return;  // someone else's run on this domain
  if (status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT)
    peers_.discovered(prefix, *who, ParticipantTags::decode(info.info.m_userData.data_vec()));
  else if (status == rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT)
    peers_.left(prefix);
  else if (status == rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT)
    peers_.dropped(prefix);
  else if (status == rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT)
    peers_.changed(prefix, ParticipantTags::decode(info.info.m_userData.data_vec()));
}

#if HAVE_SECURITY
void ParticipantDiscoveryListener::onParticipantAuthentication(
    dds::DomainParticipant*, rtps::ParticipantAuthenticationInfo&& info) {
  if (*muted_) return;
  if (info.status == rtps::ParticipantAuthenticationInfo::AUTHORIZED_PARTICIPANT)
    peers_.authenticated(info.guid.guidPrefix);
  if (!trace_.on()) return;
  room_.with_lock([&] {
    trace_("authentication of %s: %s", peers_.describe_locked(info.guid.guidPrefix).c_str(),
           info.status == rtps::ParticipantAuthenticationInfo::AUTHORIZED_PARTICIPANT
               ? "authorized"
               : "UNAUTHORIZED");
    return 0;
  });
}
#endif

WriterMatchListener::WriterMatchListener(Readiness& readiness, std::string name, MuteFlag muted)
    : readiness_(readiness), name_(std::move(name)), muted_(std::move(muted)) {}

void WriterMatchListener::on_publication_matched(dds::DataWriter*,
                                                 const dds::PublicationMatchedStatus& st) {
  if (*muted_) return;
  readiness_.on_matched(name_, prefix_of(st.last_subscription_handle), st.current_count_change);
}

ReaderListener::ReaderListener(Readiness& readiness, PeerTracker& peers, std::string name,
                               std::function<void(dds::DataReader*)> drain, MuteFlag muted)
    : readiness_(readiness),
      peers_(peers),
      name_(std::move(name)),
      drain_(std::move(drain)),
      muted_(std::move(muted)) {}

void ReaderListener::on_data_available(dds::DataReader* reader) {
  if (*muted_) return;  // left in the retired reader; the new one receives its own copy
  drain_(reader);
}

void ReaderListener::on_subscription_matched(dds::DataReader*,
                                             const dds::SubscriptionMatchedStatus& st) {
  if (*muted_) return;
  readiness_.on_matched(name_, prefix_of(st.last_publication_handle), st.current_count_change);
}

void ReaderListener::on_liveliness_changed(dds::DataReader*,
                                           const dds::LivelinessChangedStatus& st) {
  if (*muted_) return;
  if (st.not_alive_count_change > 0) peers_.liveliness_lost(prefix_of(st.last_publication_handle));
}

}  // namespace tessera::transport
