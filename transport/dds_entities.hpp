#pragma once
// The DDS entities of one session: the participant, its publisher and subscriber
// (Partition = run id), one topic per message type, and the typed writers and readers with
// their QoS (qos.hpp) and listeners (dds_listeners.hpp). Creation registers what each
// endpoint must match with Readiness; teardown is bounded (fastdds/teardown_guard.hpp).
// Internal to transport/.

#include <atomic>
#include <cstdint>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "transport/addressed_filter.hpp"
#include "transport/dds_listeners.hpp"
#include "transport/dds_trace.hpp"
#include "transport/inbox.hpp"
#include "transport/network_profile.hpp"
#include "transport/peer_tracking.hpp"
#include "transport/qos.hpp"
#include "transport/readiness.hpp"
#include "transport/session_options.hpp"
#include "transport/topic_names.hpp"
#include "transport/transport_error.hpp"

namespace tessera::transport {

class DdsEntities {
 public:
  DdsEntities(const SessionOptions& options, const NetworkProfile& net, Mailroom& room,
              PeerTracker& peers, Readiness& readiness, const DdsTrace& trace);
  DdsEntities(const DdsEntities&) = delete;
  DdsEntities& operator=(const DdsEntities&) = delete;

  /// Creates the participant of `me` on `domain` (with DDS Security when `security` holds
  /// its properties), tells the PeerTracker its own GUID prefix, then the publisher and the
  /// subscriber. Throws TransportError naming what failed (call close() afterwards: a
  /// participant may already exist).
  /// `user_data`: the participant's USER_DATA (ParticipantTags::encode()). `prefix`: the
  /// GUID prefix to use instead of Fast DDS's own choice (nullptr: Fast DDS's).
  void open(int domain, const PeerIdentity& me,
            const std::vector<std::pair<std::string, std::string>>& security,
            const std::vector<std::uint8_t>& user_data = {}, const GuidPrefix* prefix = nullptr);

  /// Sets the current participant aside for a replacement (Session::replace_participant):
  /// its listeners fall silent at once (no discovery, match or sample of it counts any more)
  /// and the entities are forgotten here, so open() can create the next participant; the
  /// retired one exists until close_retired(). Returns its GUID prefix. Requires an open
  /// participant.
  GuidPrefix retire();
  /// Deletes the retired participants (bounded like close()). Idempotent.
  void close_retired(int exit_code, const std::string& who);
  /// Replaces the current participant's USER_DATA (peers see the change with its next
  /// announcement). Throws TransportError.
  void set_user_data(const std::vector<std::uint8_t>& user_data);
  /// The GUID prefix of the current participant (requires one).
  GuidPrefix prefix() const;

  /// A writer on topic `name` (transient-local for set-up topics, volatile otherwise) that
  /// must match the peers of `e` (kAgent: agent `agent`) before the readiness barrier passes.
  /// Throws TransportError.
  template <class PubSubType>
  void make_writer(const std::string& name, bool transient_local, Expect e,
                   std::uint32_t agent = 0);
  /// A reader on topic `name` whose samples of this run go to `deliver` (on a listener
  /// thread, in arrival order); a sample `deliver` rejects by throwing stops the session.
  /// Must match the peers of `e` before the readiness barrier passes. Throws TransportError.
  /// With `addressed`, the reader reads through a content filter (addressed_filter.hpp) that
  /// passes only the samples of that layout addressed to agent `agent`.
  template <class PubSubType, class T>
  void make_reader(const std::string& name, bool transient_local, Expect e,
                   std::function<void(T&&)> deliver,
                   std::optional<AddressedLayout> addressed = std::nullopt,
                   std::uint32_t agent = 0);

  /// The writer of topic `name`, or nullptr if this process does not write it (or is closed).
  eprosima::fastdds::dds::DataWriter* writer(const std::string& name) const;
  /// Every writer, by topic.
  const std::map<std::string, eprosima::fastdds::dds::DataWriter*>& writers() const {
    return writers_;
  }
  /// Whether the readers of topic `name` are VOLATILE (made with `transient_local` false):
  /// they never receive what its writer wrote before they matched, so the writer's
  /// acknowledged samples serve nobody (SampleWriter drops them).
  bool readers_volatile(const std::string& name) const { return volatile_topics_.count(name) > 0; }

  /// Traces what Fast DDS itself reports as matched on each endpoint next to what the
  /// listeners reported (when a barrier times out). Nothing when tracing is off.
  void trace_match_state(const char* why);

  /// Deletes every entity and the participant, retired ones included (idempotent); first
  /// makes peer losses non-fatal. A Fast DDS abort or hang in here ends the process with
  /// `exit_code`.
  void close(int exit_code, const std::string& who);

 private:
  template <class PubSubType>
  eprosima::fastdds::dds::Topic* topic(const std::string& name);
  /// Deletes `participant` and what it contains, bounded by the teardown guard; its
  /// shared-memory segment stays readable for late readers (fastdds/shm_segment_keeper.hpp).
  void delete_participant(eprosima::fastdds::dds::DomainParticipant* participant, int exit_code,
                          const std::string& who);

  const SessionOptions& opt_;
  const NetworkProfile& net_;
  Mailroom& room_;
  PeerTracker& peers_;
  Readiness& readiness_;
  const DdsTrace& trace_;

  // A participant set aside by retire(), with what its listeners need to stay valid.
  struct Retired {
    eprosima::fastdds::dds::DomainParticipant* participant = nullptr;
    std::shared_ptr<std::atomic<bool>> muted;
    std::unique_ptr<ParticipantDiscoveryListener> participant_listener;
    std::vector<std::unique_ptr<WriterMatchListener>> writer_listeners;
    std::vector<std::unique_ptr<ReaderListener>> reader_listeners;
    std::vector<std::unique_ptr<eprosima::fastdds::dds::TypeSupport>> types;
  };
  std::vector<Retired> retired_;

  std::shared_ptr<std::atomic<bool>> muted_ = std::make_shared<std::atomic<bool>>(false);
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::string, eprosima::fastdds::dds::DataWriter*> writers_;
  std::set<std::string> volatile_topics_;
  std::vector<eprosima::fastdds::dds::DataReader*> readers_;
  std::map<std::string, eprosima::fastdds::dds::DataReader*> reader_by_name_;

  std::unique_ptr<ParticipantDiscoveryListener> participant_listener_;
  std::vector<std::unique_ptr<WriterMatchListener>> writer_listeners_;
  std::vector<std::unique_ptr<ReaderListener>> reader_listeners_;
  std::vector<std::unique_ptr<eprosima::fastdds::dds::TypeSupport>> types_;
};

// ---- templates ---------------------------------------------------------------------------

template <class PubSubType>
eprosima::fastdds::dds::Topic* DdsEntities::topic(const std::string& name) {
  namespace dds = eprosima::fastdds::dds;
  auto it = topics_.find(name);
  if (it != topics_.end()) return it->second;
  types_.push_back(std::make_unique<dds::TypeSupport>(new PubSubType()));
  dds::TypeSupport& type = *types_.back();
  if (participant_->register_type(type) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
    throw TransportError("cannot register DDS type " + type.get_type_name());
  dds::Topic* t = participant_->create_topic(name, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
  if (!t) throw TransportError("cannot create DDS topic " + name);
  topics_[name] = t;
  return t;
}

template <class PubSubType>
void DdsEntities::make_writer(const std::string& name, bool transient_local, Expect e,
                              std::uint32_t agent) {
  namespace dds = eprosima::fastdds::dds;
  dds::Topic* t = topic<PubSubType>(name);
  writer_listeners_.push_back(
      std::make_unique<WriterMatchListener>(readiness_, name + "/w", muted_));
  dds::DataWriter* w = publisher_->create_datawriter(
      t,
      writer_qos(transient_local, opt_.lease_s, opt_.num_agents, net_, !is_round_topic(name),
                 is_handoff_topic(name)),
      writer_listeners_.back().get(), dds::StatusMask::publication_matched());
  if (!w) throw TransportError("cannot create DDS writer for " + name);
  writers_[name] = w;
  if (!transient_local) volatile_topics_.insert(name);
  readiness_.expect(name + "/w", e, agent);
}

template <class PubSubType, class T>
void DdsEntities::make_reader(const std::string& name, bool transient_local, Expect e,
                              std::function<void(T&&)> deliver,
                              std::optional<AddressedLayout> addressed, std::uint32_t agent) {
  namespace dds = eprosima::fastdds::dds;
  dds::Topic* t = topic<PubSubType>(name);
  dds::TopicDescription* read_from = t;
  if (addressed) {
    read_from = participant_->create_contentfilteredtopic(
        name + "_for_" + std::to_string(agent), t, addressed_expression(*addressed),
        {std::to_string(agent)}, kAddressedFilterClass);
    if (!read_from) throw TransportError("cannot create the addressed DDS reader of " + name);
  }
  // Per-round traffic is not traced sample by sample, and has no liveliness lease.
  const bool set_up_topic = !is_round_topic(name);
  auto drain = [this, deliver, set_up_topic, name](dds::DataReader* reader) {
    T sample;
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      if (sample.run_id() != opt_.run_id) continue;  // belt and braces: Partition already filters
      if (trace_.on() && set_up_topic)
        room_.with_lock([&] {
          trace_("received on %s from %s", name.c_str(),
                 peers_.describe_locked(info.sample_identity.writer_guid().guidPrefix).c_str());
          return 0;
        });
      try {
        deliver(std::move(sample));
      } catch (const std::exception& ex) {
        room_.request_stop(1, std::string("received a bad message on ") +
                                  reader->get_topicdescription()->get_name() + ": " + ex.what());
      }
      sample = T();
    }
  };
  reader_listeners_.push_back(
      std::make_unique<ReaderListener>(readiness_, peers_, name + "/r", drain, muted_));
  dds::StatusMask mask = dds::StatusMask::data_available()
                         << dds::StatusMask::subscription_matched()
                         << dds::StatusMask::liveliness_changed();
  dds::DataReader* r = subscriber_->create_datareader(
      read_from, reader_qos(transient_local, opt_.lease_s, opt_.num_agents, net_, set_up_topic),
      reader_listeners_.back().get(), mask);
  if (!r) throw TransportError("cannot create DDS reader for " + name);
  readers_.push_back(r);
  reader_by_name_[name] = r;
  readiness_.expect(name + "/r", e);
}

}  // namespace tessera::transport
