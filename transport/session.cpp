#include "transport/session.hpp"

#include <fastdds/rtps/common/InstanceHandle.h>

#include <algorithm>
#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "tesseraPubSubTypes.h"
#include "transport/message_mapping.hpp"
#include "transport/qos.hpp"
#include "transport/run_failure.hpp"
#include "transport/security.hpp"
#include "transport/teardown_guard.hpp"
#include "transport/topic_names.hpp"
#include "transport/transport_error.hpp"
#include "util/input_error.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

using Prefix = rtps::GuidPrefix_t;

Prefix prefix_of(const rtps::InstanceHandle_t& handle) {
  return rtps::iHandle2GUID(handle).guidPrefix;
}

// Bound on deleting the participant at exit (normally well under a second).
constexpr double kTeardownTimeoutS = 5.0;

// Which peers an endpoint must match before the readiness barrier can pass.
enum class Expect { kNone, kOtherAgents, kOtherAgentsAndCoordinator, kCoordinator, kAllAgents };

}  // namespace

struct Session::Impl {
  SessionOptions opt;
  NetworkProfile net;  // network_profile(opt.network)
  int domain = 0;
  PeerIdentity me;
  Mailroom room;
  Inbox<wire::AgentAnnouncement> announce_in{room};
  Inbox<wire::PartitionAssignment> assignment_in{room};
  Inbox<wire::MeasurementHandoff> handoff_in{room};
  Inbox<wire::MeasurementHandoff> replica_in{room};  // purpose 1: replicas of peers' data
  Inbox<ProtocolMessage> protocol_in{room};
  Inbox<wire::RoundStatus> status_in{room};
  Inbox<wire::FinalEstimate> final_in{room};
  Inbox<wire::Control> rejoin_in{room};
  Inbox<wire::Control> rollback_in{room};
  std::uint32_t epoch = 0;  // guarded by room.mutex()
  // Protocol id of this agent in the current epoch (its agent id until a re-partition for
  // survivors renumbers them), guarded by room.mutex().
  std::uint32_t protocol_id = 0;
  // Newer epochs' messages, held with their routing: whether one is for this agent is only
  // known once this agent has its protocol id of that epoch.
  struct Held {
    std::uint32_t epoch, sender;
    bool broadcast;
    std::vector<std::uint32_t> recipients;
    ProtocolMessage message;
  };
  std::vector<Held> future;

  // State below is guarded by room.mutex().
  std::map<Prefix, PeerIdentity> peers;  // participants of this run, by GUID prefix
  std::set<Prefix> lost;
  std::map<std::string, std::multiset<Prefix>>
      matched;  // endpoint name -> matched remote participants
  std::map<std::string, Expect> expect;
  std::set<std::string> ready_from;  // describe() of peers that published READY
  bool finished_flag = false;
  bool loss_fatal = true;
  bool tolerate_agent_loss = false;

  std::atomic<std::uint64_t> bytes{0}, messages{0}, retries{0};

  // ---- tracing: TESSERA_DDS_TRACE=1 (or --verbose) prints every discovery, match and
  // barrier event with the time since the session started, to see where a process waits.
  bool trace_on = false;
  std::chrono::steady_clock::time_point t_start = std::chrono::steady_clock::now();
  void trace(const char* fmt, ...) const __attribute__((format(printf, 2, 3))) {
    if (!trace_on) return;
    char text[512];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(text, sizeof(text), fmt, args);
    va_end(args);
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    std::fprintf(stderr, "[dds %8.3f %s] %s\n", t, participant_name(me).c_str(), text);
  }
  // Who a GUID prefix is (for traces; requires room.mutex() unless tracing is off).
  std::string describe_locked(const Prefix& p) const {
    auto it = peers.find(p);
    if (it != peers.end()) return it->second.describe() + (lost.count(p) ? " (lost)" : "");
    std::ostringstream os;
    os << "unknown " << p;
    return os.str();
  }

  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  Prefix own_prefix;
  std::map<std::string, dds::Topic*> topics;
  std::map<std::string, dds::DataWriter*> writers;
  std::vector<dds::DataReader*> readers;
  std::map<std::string, dds::DataReader*> reader_by_name;

  // ---- listeners -------------------------------------------------------------------------
  struct ParticipantListener : dds::DomainParticipantListener {
    Impl* s;
    explicit ParticipantListener(Impl* impl) : s(impl) {}
    void on_participant_discovery(dds::DomainParticipant*,
                                  rtps::ParticipantDiscoveryInfo&& info) override {
      s->on_participant(info.status, info.info.m_guid.guidPrefix,
                        info.info.m_participantName.to_string());
    }
#if HAVE_SECURITY
    // Only traced: with DDS Security a peer's endpoints match only after this.
    void onParticipantAuthentication(dds::DomainParticipant*,
                                     rtps::ParticipantAuthenticationInfo&& info) override {
      if (!s->trace_on) return;
      s->room.with_lock([&] {
        s->trace("authentication of %s: %s", s->describe_locked(info.guid.guidPrefix).c_str(),
                 info.status == rtps::ParticipantAuthenticationInfo::AUTHORIZED_PARTICIPANT
                     ? "authorized"
                     : "UNAUTHORIZED");
        return 0;
      });
    }
#endif
  };

  struct WriterListener : dds::DataWriterListener {
    Impl* s;
    std::string name;
    WriterListener(Impl* impl, std::string n) : s(impl), name(std::move(n)) {}
    void on_publication_matched(dds::DataWriter*,
                                const dds::PublicationMatchedStatus& st) override {
      s->on_matched(name, prefix_of(st.last_subscription_handle), st.current_count_change);
    }
  };

  struct ReaderListener : dds::DataReaderListener {
    Impl* s;
    std::string name;
    std::function<void(dds::DataReader*)> drain;
    ReaderListener(Impl* impl, std::string n, std::function<void(dds::DataReader*)> fn)
        : s(impl), name(std::move(n)), drain(std::move(fn)) {}
    void on_data_available(dds::DataReader* reader) override { drain(reader); }
    void on_subscription_matched(dds::DataReader*,
                                 const dds::SubscriptionMatchedStatus& st) override {
      s->on_matched(name, prefix_of(st.last_publication_handle), st.current_count_change);
    }
    void on_liveliness_changed(dds::DataReader*, const dds::LivelinessChangedStatus& st) override {
      if (st.not_alive_count_change > 0)
        s->on_liveliness_lost(prefix_of(st.last_publication_handle));
    }
  };

  std::unique_ptr<ParticipantListener> participant_listener;
  std::vector<std::unique_ptr<WriterListener>> writer_listeners;
  std::vector<std::unique_ptr<ReaderListener>> reader_listeners;
  std::vector<std::unique_ptr<dds::TypeSupport>> types;

  // ---- discovery and failure -------------------------------------------------------------
  void on_participant(rtps::ParticipantDiscoveryInfo::DISCOVERY_STATUS status, const Prefix& prefix,
                      const std::string& name) {
    if (prefix == own_prefix) return;
    if (trace_on) {
      std::ostringstream os;
      os << prefix;
      trace("participant %s: '%s' %s",
            status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT    ? "discovered"
            : status == rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT     ? "removed"
            : status == rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT     ? "dropped"
            : status == rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT ? "changed"
                                                                                : "ignored",
            name.c_str(), os.str().c_str());
    }
    auto who = parse_participant_name(name);
    if (!who || who->run_id != opt.run_id) return;  // someone else's run on this domain
    if (status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) {
      std::string clash;
      room.with_lock([&] {
        for (const auto& [p, id] : peers)
          if (p != prefix && !lost.count(p) && id.coordinator == who->coordinator &&
              id.agent_id == who->agent_id)
            clash = who->describe();
        if (!who->coordinator && who->agent_id == me.agent_id && !me.coordinator)
          clash = who->describe();
        if (who->coordinator && me.coordinator) clash = who->describe();
        peers[prefix] = *who;
        return 0;
      });
      if (opt.verbose)
        std::fprintf(stderr, "%s: discovered %s\n", participant_name(me).c_str(),
                     who->describe().c_str());
      room.notify();
      if (!clash.empty())
        room.request_stop(2, "two processes claim to be " + clash + " of run '" + opt.run_id +
                                 "' (check --id / --run-id)");
    } else if (status == rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT) {
      peer_gone(prefix, "left the run", /*graceful=*/true);
    } else if (status == rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT) {
      char buf[96];
      std::snprintf(buf, sizeof(buf), "stopped responding (participant lease of %.1f s expired)",
                    opt.lease_s);
      peer_gone(prefix, buf);
    }
  }

  void on_liveliness_lost(const Prefix& prefix) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "stopped responding (writer liveliness of %.1f s lost)",
                  opt.lease_s);
    peer_gone(prefix, buf);
  }

  void peer_gone(const Prefix& prefix, const std::string& how, bool graceful = false) {
    std::optional<PeerIdentity> who;
    bool fatal = false;
    room.with_lock([&] {
      auto it = peers.find(prefix);
      if (it != peers.end() && !lost.count(prefix)) {
        lost.insert(prefix);
        who = it->second;
        fatal = loss_fatal && !(tolerate_agent_loss && !it->second.coordinator);
      }
      return 0;
    });
    if (!who) return;
    if (opt.verbose)
      std::fprintf(stderr, "%s: lost %s: %s\n", participant_name(me).c_str(),
                   who->describe().c_str(), how.c_str());
    room.notify();
    if (!fatal) return;
    const std::string why = "lost " + who->describe() + " of run '" + opt.run_id + "': it " + how;
    // A peer that left cleanly has (almost always) sent or seen an ABORT that says why;
    // give it a moment to arrive so the message names the cause, not the symptom.
    if (graceful)
      room.request_stop_after(1, why, Seconds(2.0));
    else
      room.request_stop(1, why);
  }

  void on_matched(const std::string& endpoint, const Prefix& prefix, int change) {
    if (prefix == own_prefix) return;
    room.with_lock([&] {
      auto& set = matched[endpoint];
      if (change > 0) {
        set.insert(prefix);
      } else if (change < 0) {
        auto it = set.find(prefix);
        if (it != set.end()) set.erase(it);
      }
      trace("%s %s %s (change %+d, now %zu)", endpoint.c_str(),
            change > 0   ? "matched"
            : change < 0 ? "unmatched"
                         : "match event without change from",
            describe_locked(prefix).c_str(), change, set.size());
      return 0;
    });
    room.notify();
  }

  // A protocol message of `e`: delivered, held or dropped by epoch (see Session::set_epoch).
  void deliver_protocol(std::uint32_t e, std::uint32_t sender, bool broadcast,
                        const std::vector<std::uint32_t>& recipients, ProtocolMessage&& m) {
    bool wake = false;
    room.with_lock([&] {
      if (e == epoch) {
        if (sender != protocol_id && addressed_to(broadcast, recipients, protocol_id)) {
          protocol_in.push_locked(std::move(m));
          wake = true;
        }
      } else if (e > epoch) {
        future.push_back(Held{e, sender, broadcast, recipients, std::move(m)});
      }
      return 0;
    });
    if (wake) room.notify();
  }

  // ---- readiness -------------------------------------------------------------------------
  std::vector<PeerIdentity> expected_peers(Expect e) const {
    std::vector<PeerIdentity> out;
    if (!opt.expect_coordinator) {
      if (e == Expect::kCoordinator) e = Expect::kNone;
      if (e == Expect::kOtherAgentsAndCoordinator) e = Expect::kOtherAgents;
    }
    auto agent = [&](std::uint32_t k) { return PeerIdentity{opt.run_id, false, k}; };
    switch (e) {
      case Expect::kNone:
        break;
      case Expect::kCoordinator:
        out.push_back(PeerIdentity{opt.run_id, true, 0});
        break;
      case Expect::kOtherAgentsAndCoordinator:
        out.push_back(PeerIdentity{opt.run_id, true, 0});
        [[fallthrough]];
      case Expect::kOtherAgents:
        for (std::uint32_t k = 0; k < opt.num_agents; ++k)
          if (me.coordinator || k != me.agent_id) out.push_back(agent(k));
        break;
      case Expect::kAllAgents:
        for (std::uint32_t k = 0; k < opt.num_agents; ++k) out.push_back(agent(k));
        break;
    }
    return out;
  }

  // Requires room.mutex() held.
  bool matched_locked(std::string* missing) const {
    std::set<std::string> absent;
    for (const auto& [endpoint, e] : expect) {
      std::set<std::string> have;
      auto it = matched.find(endpoint);
      if (it != matched.end())
        for (const Prefix& p : it->second) {
          auto peer = peers.find(p);
          if (peer != peers.end() && !lost.count(p)) have.insert(peer->second.describe());
        }
      for (const auto& want : expected_peers(e))
        if (!have.count(want.describe())) absent.insert(want.describe());
    }
    if (missing) {
      missing->clear();
      for (const auto& a : absent) *missing += (missing->empty() ? "" : ", ") + a;
    }
    return absent.empty();
  }

  // What Fast DDS itself reports as matched on each endpoint next to what the listeners
  // told us (for the trace when a barrier times out).
  void trace_match_state(const char* why) {
    if (!trace_on) return;
    for (const auto& [name, w] : writers) {
      std::vector<rtps::InstanceHandle_t> handles;
      ReturnCode_t rc = w->get_matched_subscriptions(handles);
      std::string who;
      room.with_lock([&] {
        for (const auto& h : handles) who += " " + describe_locked(prefix_of(h));
        auto it = matched.find(name + "/w");
        who += " | listener:";
        if (it != matched.end())
          for (const auto& p : it->second) who += " " + describe_locked(p);
        return 0;
      });
      trace("%s: %s/w rc %d fastdds:%s", why, name.c_str(), static_cast<int>(rc()), who.c_str());
    }
    for (const auto& [name, r] : reader_by_name) {
      std::vector<rtps::InstanceHandle_t> handles;
      ReturnCode_t rc = r->get_matched_publications(handles);
      std::string who;
      room.with_lock([&] {
        for (const auto& h : handles) who += " " + describe_locked(prefix_of(h));
        auto it = matched.find(name + "/r");
        who += " | listener:";
        if (it != matched.end())
          for (const auto& p : it->second) who += " " + describe_locked(p);
        return 0;
      });
      trace("%s: %s/r rc %d fastdds:%s", why, name.c_str(), static_cast<int>(rc()), who.c_str());
    }
  }

  // ---- entities --------------------------------------------------------------------------
  template <class PubSubType>
  dds::Topic* topic(const std::string& name) {
    auto it = topics.find(name);
    if (it != topics.end()) return it->second;
    types.push_back(std::make_unique<dds::TypeSupport>(new PubSubType()));
    dds::TypeSupport& type = *types.back();
    if (participant->register_type(type) != ReturnCode_t::RETCODE_OK)
      throw TransportError("cannot register DDS type " + type.get_type_name());
    dds::Topic* t = participant->create_topic(name, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (!t) throw TransportError("cannot create DDS topic " + name);
    topics[name] = t;
    return t;
  }

  template <class PubSubType>
  void make_writer(const std::string& name, bool transient_local, Expect e) {
    dds::Topic* t = topic<PubSubType>(name);
    writer_listeners.push_back(std::make_unique<WriterListener>(this, name + "/w"));
    dds::DataWriter* w = publisher->create_datawriter(
        t, writer_qos(transient_local, opt.lease_s, opt.num_agents, net),
        writer_listeners.back().get(), dds::StatusMask::publication_matched());
    if (!w) throw TransportError("cannot create DDS writer for " + name);
    writers[name] = w;
    if (e != Expect::kNone) expect[name + "/w"] = e;
  }

  template <class PubSubType, class T>
  void make_reader(const std::string& name, bool transient_local, Expect e,
                   std::function<void(T&&)> deliver) {
    dds::Topic* t = topic<PubSubType>(name);
    const bool set_up_topic = name != kBlockTopic && name != kStatusTopic;
    auto drain = [this, deliver, set_up_topic, name](dds::DataReader* reader) {
      T sample;
      dds::SampleInfo info;
      while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        if (sample.run_id() != opt.run_id) continue;  // belt and braces: Partition already filters
        if (trace_on && set_up_topic)
          room.with_lock([&] {
            trace("received on %s from %s", name.c_str(),
                  describe_locked(info.sample_identity.writer_guid().guidPrefix).c_str());
            return 0;
          });
        try {
          deliver(std::move(sample));
        } catch (const std::exception& ex) {
          room.request_stop(1, std::string("received a bad message on ") +
                                   reader->get_topicdescription()->get_name() + ": " + ex.what());
        }
        sample = T();
      }
    };
    reader_listeners.push_back(std::make_unique<ReaderListener>(this, name + "/r", drain));
    dds::StatusMask mask = dds::StatusMask::data_available()
                           << dds::StatusMask::subscription_matched()
                           << dds::StatusMask::liveliness_changed();
    dds::DataReader* r = subscriber->create_datareader(
        t, reader_qos(transient_local, opt.lease_s, opt.num_agents, net),
        reader_listeners.back().get(), mask);
    if (!r) throw TransportError("cannot create DDS reader for " + name);
    readers.push_back(r);
    reader_by_name[name] = r;
    if (e != Expect::kNone) expect[name + "/r"] = e;
  }

  template <class T>
  void write(const std::string& name, const T& sample) {
    auto it = writers.find(name);
    if (it == writers.end())
      throw TransportError("this " + std::string(me.coordinator ? "coordinator" : "agent") +
                           " does not write " + name);
    dds::DataWriter* w = it->second;
    const auto deadline =
        std::chrono::steady_clock::now() +
        std::chrono::duration_cast<std::chrono::nanoseconds>(Seconds(opt.write_timeout_s));
    for (;;) {
      // The handle overload reports why a write failed (the plain one only returns a bool).
      ReturnCode_t rc = w->write(const_cast<T*>(&sample), rtps::c_InstanceHandle_Unknown);
      if (rc == ReturnCode_t::RETCODE_OK) {
        bytes += serialized_size(sample);
        ++messages;
        return;
      }
      if (rc == ReturnCode_t::RETCODE_BAD_PARAMETER || rc == ReturnCode_t::RETCODE_NOT_ENABLED ||
          rc == ReturnCode_t::RETCODE_PRECONDITION_NOT_MET ||
          rc == ReturnCode_t::RETCODE_ILLEGAL_OPERATION)
        throw TransportError("DDS write on " + name + " failed (return code " +
                             std::to_string(rc()) + ")");
      // Most likely the bounded history is full of unacknowledged samples (2.9 reports that
      // as OUT_OF_RESOURCES, TIMEOUT or ERROR): wait for acknowledgements (not a busy loop),
      // then try again, until the deadline.
      ++retries;
      trace("write on %s: history full (return code %u), waiting for acknowledgements",
            name.c_str(), rc());
      if (std::chrono::steady_clock::now() > deadline) {
        char buf[64];
        std::snprintf(buf, sizeof(buf), "%g s (return code %u)", opt.write_timeout_s, rc());
        throw TransportError("could not send on " + name + " within " + buf +
                             ": the receivers do not acknowledge (history full)");
      }
      w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 20000000));
    }
  }

  void close(int exit_code) {
    if (!participant) return;
    room.with_lock([&] {
      loss_fatal = false;
      return 0;
    });
    trace("closing: deleting the DDS entities and the participant");
    {
      // Fast DDS 2.9 may abort or deadlock in here (transport/teardown_guard.hpp).
      TeardownGuard guard(exit_code, participant_name(me), Seconds(kTeardownTimeoutS));
      participant->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    }
    participant = nullptr;
    writers.clear();
    readers.clear();
    reader_by_name.clear();
    topics.clear();
  }
};

Session::Session(const SessionOptions& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  Impl& s = *impl_;
  s.opt = options;
  s.tolerate_agent_loss = options.tolerate_agent_loss;
  s.net = network_profile(options.network);
  if (const char* env = std::getenv("TESSERA_DDS_TRACE"); env && *env && *env != '0')
    s.trace_on = true;
  std::vector<std::pair<std::string, std::string>> security;
  if (!options.security_dir.empty())
    security = security_properties(security_files(
        options.security_dir, security_identity(options.coordinator, options.agent_id)));
  s.domain = options.domain >= 0 ? options.domain : domain_for_run(options.run_id);
  s.me = PeerIdentity{options.run_id, options.coordinator,
                      options.coordinator ? 0u : options.agent_id};
  s.protocol_id = s.me.agent_id;

  // TESSERA_DDS_LOG=1 shows Fast DDS's own warnings and errors (for diagnosing QoS trouble).
  if (const char* env = std::getenv("TESSERA_DDS_LOG"); env && *env && *env != '0')
    eprosima::fastdds::dds::Log::SetVerbosity(eprosima::fastdds::dds::Log::Kind::Warning);
  s.participant_listener = std::make_unique<Impl::ParticipantListener>(&s);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  s.participant = factory->create_participant(
      s.domain,
      participant_qos(participant_name(s.me), options.lease_s, options.initial_peers, s.domain,
                      options.num_agents, s.net, security, options.shared_memory),
      s.participant_listener.get(), dds::StatusMask::none());
  if (!s.participant)
    throw TransportError("cannot create a DDS participant on domain " + std::to_string(s.domain) +
                         (security.empty()
                              ? std::string()
                              : " with DDS Security from " + options.security_dir +
                                    " (certificate, key, permissions or governance rejected; "
                                    "TESSERA_DDS_LOG=1 shows Fast DDS's reason)"));
  s.own_prefix = s.participant->guid().guidPrefix;
  try {
    s.publisher = s.participant->create_publisher(publisher_qos(options.run_id));
    s.subscriber = s.participant->create_subscriber(subscriber_qos(options.run_id));
    if (!s.publisher || !s.subscriber)
      throw TransportError("cannot create DDS publisher/subscriber");

    const std::uint32_t me = s.me.agent_id;
    if (options.coordinator) {
      s.make_writer<wire::PartitionAssignmentPubSubType>(kAssignmentTopic, true, Expect::kNone);
      s.make_writer<wire::ControlPubSubType>(kControlTopic, true, Expect::kNone);
      s.make_reader<wire::AgentAnnouncementPubSubType, wire::AgentAnnouncement>(
          kAnnounceTopic, true, Expect::kNone,
          [&s](wire::AgentAnnouncement&& m) { s.announce_in.push(std::move(m)); });
      s.make_reader<wire::RoundStatusPubSubType, wire::RoundStatus>(
          kStatusTopic, false, Expect::kAllAgents,
          [&s](wire::RoundStatus&& m) { s.status_in.push(std::move(m)); });
      s.make_reader<wire::FinalEstimatePubSubType, wire::FinalEstimate>(
          kFinalTopic, false, Expect::kAllAgents,
          [&s](wire::FinalEstimate&& m) { s.final_in.push(std::move(m)); });
    } else {
      s.make_writer<wire::AgentAnnouncementPubSubType>(kAnnounceTopic, true, Expect::kNone);
      s.make_writer<wire::ControlPubSubType>(kControlTopic, true, Expect::kNone);
      s.make_writer<wire::MeasurementHandoffPubSubType>(kHandoffTopic, false, Expect::kOtherAgents);
      s.make_writer<wire::PoseBlockPubSubType>(kBlockTopic, false, Expect::kOtherAgents);
      s.make_writer<wire::RoundStatusPubSubType>(kStatusTopic, false,
                                                 Expect::kOtherAgentsAndCoordinator);
      s.make_writer<wire::FinalEstimatePubSubType>(kFinalTopic, false, Expect::kCoordinator);
      s.make_reader<wire::PartitionAssignmentPubSubType, wire::PartitionAssignment>(
          kAssignmentTopic, true, Expect::kNone,
          [&s](wire::PartitionAssignment&& m) { s.assignment_in.push(std::move(m)); });
      s.make_reader<wire::MeasurementHandoffPubSubType, wire::MeasurementHandoff>(
          kHandoffTopic, false, Expect::kOtherAgents, [&s, me](wire::MeasurementHandoff&& m) {
            if (m.recipient() != me || m.sender() == me) return;
            if (m.purpose() == 1)
              s.replica_in.push(std::move(m));
            else
              s.handoff_in.push(std::move(m));
          });
      s.make_reader<wire::PoseBlockPubSubType, wire::PoseBlock>(
          kBlockTopic, false, Expect::kOtherAgents, [&s](wire::PoseBlock&& m) {
            s.deliver_protocol(m.epoch(), m.sender(), m.broadcast(), m.recipients(),
                               ProtocolMessage(from_wire(m)));
          });
      s.make_reader<wire::RoundStatusPubSubType, wire::RoundStatus>(
          kStatusTopic, false, Expect::kOtherAgents, [&s](wire::RoundStatus&& m) {
            s.deliver_protocol(m.epoch(), m.sender(), m.broadcast(), m.recipients(),
                               ProtocolMessage(from_wire(m)));
          });
    }
    // Control: everyone reads everyone (READY barrier, ABORT, FINISHED).
    const std::uint32_t self_id = options.coordinator ? kCoordinatorId : me;
    s.make_reader<wire::ControlPubSubType, wire::Control>(
        kControlTopic, true, Expect::kNone, [&s, self_id](wire::Control&& m) {
          if (m.sender() == self_id) return;
          PeerIdentity from{s.opt.run_id, m.sender() == kCoordinatorId,
                            m.sender() == kCoordinatorId ? 0u : m.sender()};
          switch (m.kind()) {
            case wire::CONTROL_READY:
              s.room.with_lock([&] { return s.ready_from.insert(from.describe()).second; });
              s.trace("READY from %s", from.describe().c_str());
              s.room.notify();
              break;
            case wire::CONTROL_FINISHED:
              s.room.with_lock([&] { return s.finished_flag = true; });
              s.room.notify();
              break;
            case wire::CONTROL_ABORT:
              s.room.request_stop(
                  1, from.describe() + " aborted run '" + s.opt.run_id + "': " + m.reason(), true);
              break;
            case wire::CONTROL_REJOIN:
              if (s.opt.coordinator) s.rejoin_in.push(std::move(m));
              break;
            case wire::CONTROL_ROLLBACK:
              if (!s.opt.coordinator && m.sender() == kCoordinatorId)
                s.rollback_in.push(std::move(m));
              break;
          }
        });
  } catch (...) {
    s.close(kExitRunFailed);
    throw;
  }
}

Session::~Session() {
  close();
}

const SessionOptions& Session::options() const {
  return impl_->opt;
}
int Session::domain() const {
  return impl_->domain;
}
PeerIdentity Session::self() const {
  return impl_->me;
}
Mailroom& Session::mailroom() {
  return impl_->room;
}

Inbox<wire::AgentAnnouncement>& Session::announcements() {
  return impl_->announce_in;
}
Inbox<wire::PartitionAssignment>& Session::assignments() {
  return impl_->assignment_in;
}
Inbox<wire::MeasurementHandoff>& Session::handoffs() {
  return impl_->handoff_in;
}
Inbox<wire::MeasurementHandoff>& Session::replicas() {
  return impl_->replica_in;
}
Inbox<ProtocolMessage>& Session::protocol() {
  return impl_->protocol_in;
}
Inbox<wire::RoundStatus>& Session::status_watch() {
  return impl_->status_in;
}
Inbox<wire::FinalEstimate>& Session::finals() {
  return impl_->final_in;
}
Inbox<wire::Control>& Session::rejoins() {
  return impl_->rejoin_in;
}
Inbox<wire::Control>& Session::rollbacks() {
  return impl_->rollback_in;
}

std::uint32_t Session::epoch() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  return impl_->epoch;
}

void Session::set_epoch(std::uint32_t e) {
  set_epoch(e, protocol_id());
}

std::uint32_t Session::protocol_id() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  return impl_->protocol_id;
}

void Session::set_epoch(std::uint32_t e, std::uint32_t protocol_id) {
  Impl& s = *impl_;
  s.room.with_lock([&] {
    if (e < s.epoch) return 0;
    s.epoch = e;
    s.protocol_id = protocol_id;
    s.protocol_in.clear_locked();  // everything queued is of an older epoch
    std::vector<Impl::Held> later;
    for (auto& h : s.future) {
      if (h.epoch == e) {
        if (h.sender != protocol_id && addressed_to(h.broadcast, h.recipients, protocol_id))
          s.protocol_in.push_locked(std::move(h.message));
      } else if (h.epoch > e) {
        later.push_back(std::move(h));
      }
    }
    s.future = std::move(later);
    return 0;
  });
  s.room.notify();
}

void Session::publish(const wire::AgentAnnouncement& m) {
  impl_->write(kAnnounceTopic, m);
}
void Session::publish(const wire::PartitionAssignment& m) {
  impl_->write(kAssignmentTopic, m);
}
void Session::publish(const wire::MeasurementHandoff& m) {
  impl_->write(kHandoffTopic, m);
}
void Session::publish(const wire::FinalEstimate& m) {
  impl_->write(kFinalTopic, m);
}

void Session::send(const OutgoingMessage& m) {
  const std::string& run = impl_->opt.run_id;
  const std::uint32_t e = epoch();
  if (const auto* block = std::get_if<PoseBlockMessage>(&m.message)) {
    wire::PoseBlock w = to_wire_block(*block, run, m.broadcast, m.recipients);
    w.epoch(e);
    impl_->write(kBlockTopic, w);
  } else {
    wire::RoundStatus w =
        to_wire_status(std::get<RoundStatusMessage>(m.message), run, m.broadcast, m.recipients);
    w.epoch(e);
    impl_->write(kStatusTopic, w);
  }
}

void Session::send_control(wire::ControlKind kind, const std::string& reason) {
  wire::Control c;
  c.run_id(impl_->opt.run_id);
  c.sender(impl_->me.coordinator ? kCoordinatorId : impl_->me.agent_id);
  c.kind(kind);
  c.reason(reason);
  impl_->write(kControlTopic, c);
}

void Session::send_control(wire::Control c) {
  c.run_id(impl_->opt.run_id);
  c.sender(impl_->me.coordinator ? kCoordinatorId : impl_->me.agent_id);
  impl_->write(kControlTopic, c);
}

bool Session::endpoints_matched(std::string* missing) const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  return impl_->matched_locked(missing);
}

WaitStatus Session::ready_barrier(Seconds timeout, std::string* missing) {
  Impl& s = *impl_;
  const auto start = std::chrono::steady_clock::now();
  std::string absent;
  s.trace("barrier: waiting for endpoints to match");
  WaitStatus st = s.room.wait_for([&] { return s.matched_locked(&absent); }, timeout);
  if (st != WaitStatus::kReady) {
    if (missing) *missing = "endpoints not matched with " + absent;
    s.trace("barrier: endpoints not matched with %s", absent.c_str());
    s.trace_match_state("barrier timeout");
    return st;
  }
  s.trace("barrier: endpoints matched, sending READY");
  send_control(wire::CONTROL_READY);
  std::vector<PeerIdentity> others = s.expected_peers(Expect::kOtherAgents);
  if (!s.me.coordinator && s.opt.expect_coordinator)
    others.push_back(PeerIdentity{s.opt.run_id, true, 0});
  const Seconds left = timeout - (std::chrono::steady_clock::now() - start);
  st = s.room.wait_for(
      [&] {
        absent.clear();
        for (const auto& p : others)
          if (!s.ready_from.count(p.describe()))
            absent += (absent.empty() ? "" : ", ") + p.describe();
        return absent.empty();
      },
      left);
  if (st == WaitStatus::kTimeout && missing) *missing = "no READY from " + absent;
  if (st == WaitStatus::kTimeout) {
    s.trace("barrier: no READY from %s", absent.c_str());
    s.trace_match_state("barrier timeout");
  } else if (st == WaitStatus::kReady) {
    s.trace("barrier: passed");
  }
  return st;
}

bool Session::finished() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  return impl_->finished_flag;
}

WaitStatus Session::wait_finished(Seconds timeout) {
  return impl_->room.wait_for([&] { return impl_->finished_flag; }, timeout);
}

std::vector<PeerIdentity> Session::live_peers() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  std::vector<PeerIdentity> out;
  for (const auto& [p, who] : impl_->peers)
    if (!impl_->lost.count(p)) out.push_back(who);
  return out;
}

std::size_t Session::peers_ever_seen() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  return impl_->peers.size();
}

void Session::set_peer_loss_fatal(bool fatal) {
  impl_->room.with_lock([&] { return impl_->loss_fatal = fatal; });
}

void Session::set_agent_loss_tolerated(bool tolerated) {
  impl_->room.with_lock([&] { return impl_->tolerate_agent_loss = tolerated; });
}

std::vector<std::uint32_t> Session::lost_agents() const {
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  std::set<std::uint32_t> lost, live;
  for (const auto& [p, who] : impl_->peers) {
    if (who.coordinator) continue;
    (impl_->lost.count(p) ? lost : live).insert(who.agent_id);
  }
  std::vector<std::uint32_t> out;
  for (auto k : lost)
    if (!live.count(k)) out.push_back(k);
  return out;
}

void Session::flush(Seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
  for (auto& [name, w] : impl_->writers) {
    (void)name;
    double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return;
    w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(left));
  }
}

void Session::linger_for_control(Seconds timeout, Seconds unseen_patience) {
  Impl& s = *impl_;
  const auto start = std::chrono::steady_clock::now();
  std::vector<PeerIdentity> others = s.expected_peers(Expect::kOtherAgents);
  if (!s.me.coordinator && s.opt.expect_coordinator)
    others.push_back(PeerIdentity{s.opt.run_id, true, 0});
  const std::string endpoint = std::string(kControlTopic) + "/w";
  // Every expected peer has matched our control writer or is gone; with `include_unseen`
  // false, peers never discovered are not waited for.
  auto reached = [&](bool include_unseen) {
    std::set<std::string> have, seen;
    auto it = s.matched.find(endpoint);
    if (it != s.matched.end())
      for (const Prefix& p : it->second) {
        auto peer = s.peers.find(p);
        if (peer != s.peers.end()) have.insert(peer->second.describe());
      }
    for (const auto& [p, who] : s.peers) {
      seen.insert(who.describe());
      if (s.lost.count(p)) have.insert(who.describe());  // no point waiting for a peer that is gone
    }
    for (const auto& p : others)
      if (!have.count(p.describe()) && (include_unseen || seen.count(p.describe()))) return false;
    return true;
  };
  // A peer never seen may still be starting: wait for it, but only `unseen_patience`.
  const Seconds first = std::min(timeout, unseen_patience);
  if (s.room.wait_for([&] { return reached(true); }, first, /*interruptible=*/false) !=
      WaitStatus::kReady)
    s.room.wait_for([&] { return reached(false); }, timeout - first, /*interruptible=*/false);
  const double left = (timeout - (std::chrono::steady_clock::now() - start)).count();
  auto w = s.writers.find(kControlTopic);
  if (left > 0 && w != s.writers.end())
    w->second->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(left));
}

SessionStats Session::stats() const {
  return SessionStats{impl_->bytes.load(), impl_->messages.load(), impl_->retries.load()};
}

void Session::close() {
  close(kExitRunFailed);
}

void Session::close(int exit_code) {
  if (impl_) impl_->close(exit_code);
}

}  // namespace tessera::transport
