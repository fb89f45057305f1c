#include "transport/dds_entities.hpp"

#include <fastdds/rtps/common/InstanceHandle.h>

#include <atomic>
#include <cstdlib>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>

#include "transport/fastdds/discovery_port.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/fastdds/shm_segment_keeper.hpp"
#include "transport/fastdds/teardown_guard.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {
// Bound on deleting the participant at exit (normally well under a second).
constexpr double kTeardownTimeoutS = 5.0;
}  // namespace

DdsEntities::DdsEntities(const SessionOptions& options, const NetworkProfile& net, Mailroom& room,
                         PeerTracker& peers, Readiness& readiness, const DdsTrace& trace)
    : opt_(options), net_(net), room_(room), peers_(peers), readiness_(readiness), trace_(trace) {}

void DdsEntities::open(int domain, const PeerIdentity& me,
                       const std::vector<std::pair<std::string, std::string>>& security,
                       const std::vector<std::uint8_t>& user_data, const GuidPrefix* prefix) {
  // TESSERA_DDS_LOG=1 shows Fast DDS's own warnings and errors (for diagnosing QoS trouble);
  // the stuck shared-memory listener is counted either way (fastdds/shm_receive_watch.hpp).
  watch_fastdds_log();
  participant_listener_ =
      std::make_unique<ParticipantDiscoveryListener>(peers_, opt_.run_id, room_, trace_, muted_);
  dds::DomainParticipantQos qos = participant_qos(
      participant_name(me), opt_.lease_s, opt_.initial_peers, domain, opt_.num_agents, net_,
      security, opt_.uses_shared_memory(), user_data, opt_.uses_udp());
  if (prefix) qos.wire_protocol().prefix = *prefix;
  // Participant id (where Fast DDS starts looking for free ports of this host): the role's
  // own, 0 for the coordinator and k + 1 for agent k, instead of Fast DDS's per-process
  // counter. Every process of a run starts that counter at 0, so agent k probed (opened and
  // closed) the ports of k + 1 participants already there before finding free ones. A taken
  // id still works: Fast DDS then moves on to the next ports as before (another run on the
  // domain). Only for a process's first participant: another one in the same process with
  // the same id is refused by Fast DDS (tests hold several sessions), hence also the retry.
  static std::atomic<bool> first_in_process{true};
  const bool own_id = !prefix && first_in_process.exchange(false);
  if (own_id)
    qos.wire_protocol().participant_id = me.coordinator ? 0 : static_cast<int>(me.agent_id) + 1;
  const std::uint32_t local = local_discovery_participants(opt_.num_agents);
  participant_ = create_participant_with_discovery_port(domain, qos, participant_listener_.get(),
                                                        dds::StatusMask::none(), local);
  if (!participant_ && own_id) {
    qos.wire_protocol().participant_id = -1;
    participant_ = create_participant_with_discovery_port(domain, qos, participant_listener_.get(),
                                                          dds::StatusMask::none(), local);
  }
  if (!participant_)
    throw TransportError("cannot create a DDS participant on domain " + std::to_string(domain) +
                         (security.empty()
                              ? std::string()
                              : " with DDS Security from " + opt_.security_dir +
                                    " (certificate, key, permissions or governance rejected; "
                                    "TESSERA_DDS_LOG=1 shows Fast DDS's reason)"));
  peers_.add_own_prefix(participant_->guid().guidPrefix);
  // On every participant, so that writers filter for the addressed readers.
  if (!register_addressed_filter(*participant_))
    throw TransportError("cannot register the addressed content filter");
  publisher_ = participant_->create_publisher(publisher_qos(opt_.run_id));
  subscriber_ = participant_->create_subscriber(subscriber_qos(opt_.run_id));
  if (!publisher_ || !subscriber_) throw TransportError("cannot create DDS publisher/subscriber");
}

GuidPrefix DdsEntities::prefix() const {
  return participant_->guid().guidPrefix;
}

void DdsEntities::set_user_data(const std::vector<std::uint8_t>& user_data) {
  dds::DomainParticipantQos q = participant_->get_qos();
  q.user_data().data_vec(user_data);
  if (participant_->set_qos(q) != ReturnCode_t::RETCODE_OK)
    throw TransportError("cannot change the DDS participant's user data");
}

GuidPrefix DdsEntities::retire() {
  const GuidPrefix old = participant_->guid().guidPrefix;
  muted_->store(true);
  Retired r;
  r.participant = participant_;
  r.muted = muted_;
  r.participant_listener = std::move(participant_listener_);
  r.writer_listeners = std::move(writer_listeners_);
  r.reader_listeners = std::move(reader_listeners_);
  r.types = std::move(types_);
  retired_.push_back(std::move(r));
  muted_ = std::make_shared<std::atomic<bool>>(false);
  participant_ = nullptr;
  publisher_ = nullptr;
  subscriber_ = nullptr;
  writer_listeners_.clear();
  reader_listeners_.clear();
  types_.clear();
  writers_.clear();
  readers_.clear();
  reader_by_name_.clear();
  topics_.clear();
  return old;
}

void DdsEntities::close_retired(int exit_code, const std::string& who) {
  for (Retired& r : retired_) {
    trace_("deleting a replaced participant");
    delete_participant(r.participant, exit_code, who);
  }
  retired_.clear();
}

void DdsEntities::delete_participant(dds::DomainParticipant* participant, int exit_code,
                                     const std::string& who) {
  // Peers that read our last messages late still find our shared-memory segment
  // (fastdds/shm_segment_keeper.hpp).
  ShmSegmentKeeper keeper;
  if (opt_.uses_shared_memory()) keeper.keep();
  {
    // Fast DDS 2.9 may abort or deadlock in here (transport/fastdds/teardown_guard.hpp).
    TeardownGuard guard(exit_code, who, Seconds(kTeardownTimeoutS));
    participant->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
  }
  const std::vector<std::string> restored = keeper.restore();
  const int swept = opt_.uses_shared_memory() ? sweep_kept_segments() : 0;
  trace_(
      "participant deleted: %zu shared-memory segment names kept for late readers, %d old "
      "ones removed",
      restored.size(), swept);
}

dds::DataWriter* DdsEntities::writer(const std::string& name) const {
  auto it = writers_.find(name);
  return it == writers_.end() ? nullptr : it->second;
}

void DdsEntities::trace_match_state(const char* why) {
  if (!trace_.on()) return;
  // One line per endpoint: Fast DDS's view (`handles`, `rc`) | the listeners' view.
  auto line = [&](const std::string& endpoint, ReturnCode_t rc,
                  const std::vector<rtps::InstanceHandle_t>& handles) {
    std::string who;
    room_.with_lock([&] {
      for (const auto& h : handles) who += " " + peers_.describe_locked(prefix_of(h));
      who += " | listener:" + readiness_.describe_matched_locked(endpoint);
      return 0;
    });
    trace_("%s: %s rc %d fastdds:%s", why, endpoint.c_str(), static_cast<int>(rc()), who.c_str());
  };
  for (const auto& [name, w] : writers_) {
    std::vector<rtps::InstanceHandle_t> handles;
    ReturnCode_t rc = w->get_matched_subscriptions(handles);
    line(name + "/w", rc, handles);
  }
  for (const auto& [name, r] : reader_by_name_) {
    std::vector<rtps::InstanceHandle_t> handles;
    ReturnCode_t rc = r->get_matched_publications(handles);
    line(name + "/r", rc, handles);
  }
}

void DdsEntities::close(int exit_code, const std::string& who) {
  if (!participant_ && retired_.empty()) return;
  peers_.set_loss_fatal(false);
  close_retired(exit_code, who);
  if (!participant_) return;
  trace_("closing: deleting the DDS entities and the participant");
  delete_participant(participant_, exit_code, who);
  participant_ = nullptr;
  writers_.clear();
  readers_.clear();
  reader_by_name_.clear();
  topics_.clear();
}

}  // namespace tessera::transport
