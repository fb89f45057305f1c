// tessera-dds-snoop: a participant that tries to read a Tessera run it is not part of. It
// subscribes to every Tessera topic on --domain (Partition = --run-id) and counts the samples
// it receives until --duration elapses or SIGINT / SIGTERM, then prints one line:
//   participants=P readers=R refused=T samples=S [topic=count ...]
// With --security DIR --identity NAME it authenticates with DIR/NAME (layout of
// scripts/security/make_identities.sh); without, it is an unauthenticated participant. Used
// by tests/dds_security_test.cpp to show that outsiders read nothing from a secured run
// (and, with a permitted identity, that the same tool does read a run). --name and
// --user-data set its participant's name and USER_DATA: an impostor advertising a run
// member's name ("tessera:RUN:agent:1") and tags, as anyone on the network can.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "arguments.hpp"
#include "tesseraPubSubTypes.h"
#include "transport/fastdds/discovery_port.hpp"
#include "transport/run_identity.hpp"
#include "transport/security.hpp"
#include "transport/signal_watcher.hpp"
#include "transport/topic_names.hpp"

namespace fdds = ::eprosima::fastdds::dds;  // (Fast DDS declares a global ::dds)
namespace rtps = ::eprosima::fastrtps::rtps;
using namespace tessera;
using namespace tessera::transport;

namespace {

constexpr const char* kHelp =
    "usage: tessera-dds-snoop --domain D [--run-id ID] [--duration S]\n"
    "                         [--security DIR --identity NAME]\n"
    "                         [--name PARTICIPANT_NAME] [--user-data TEXT]\n"
    "Reads every Tessera topic of run ID (Partition QoS) on domain D and prints how many\n"
    "samples arrived: participants=P readers=R refused=T samples=S topic=count...\n";

struct Counts {
  std::mutex m;
  std::map<std::string, long> per_topic;
  long participants = 0;
};

struct ParticipantListener : fdds::DomainParticipantListener {
  Counts& c;
  explicit ParticipantListener(Counts& counts) : c(counts) {}
  void on_participant_discovery(fdds::DomainParticipant*,
                                rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) {
      std::lock_guard<std::mutex> lock(c.m);
      ++c.participants;
    }
  }
};

// Counts every valid sample of one topic (taken in the listener: nothing else to do here).
template <class Sample>
struct CountingListener : fdds::DataReaderListener {
  Counts& c;
  std::string topic;
  CountingListener(Counts& counts, std::string t) : c(counts), topic(std::move(t)) {}
  void on_data_available(fdds::DataReader* reader) override {
    Sample s;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) {
        std::lock_guard<std::mutex> lock(c.m);
        ++c.per_topic[topic];
      }
  }
  using ReturnCode_t = eprosima::fastrtps::types::ReturnCode_t;
};

struct Snoop {
  Counts counts;
  fdds::DomainParticipant* participant = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  std::vector<std::unique_ptr<fdds::DataReaderListener>> listeners;
  int readers = 0;
  std::vector<std::string> refused;

  template <class PubSubType, class Sample>
  void watch(const char* name) {
    fdds::TypeSupport type(new PubSubType());
    type.register_type(participant);
    fdds::Topic* t = participant->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;  // matches the run's reliable writers
    q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;    // matches volatile and transient ones
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = 64;
    q.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    listeners.push_back(std::make_unique<CountingListener<Sample>>(counts, name));
    fdds::DataReader* r = t ? subscriber->create_datareader(t, q, listeners.back().get()) : nullptr;
    if (r)
      ++readers;
    else
      refused.push_back(name);  // access control said no (or the topic could not be made)
  }
};

}  // namespace

int main(int argc, char** argv) {
  SignalWatcher signals;
  std::vector<std::string> argv_list(argv + 1, argv + argc);
  long domain = -1;
  std::string run = "default", security, identity, name = "tessera-dds-snoop", user_data;
  double duration = 30;
  try {
    cli::Arguments args(
        argv_list, {"domain", "run-id", "duration", "security", "identity", "name", "user-data"},
        {"help"});
    if (args.has("help")) {
      std::cout << kHelp;
      return 0;
    }
    domain = args.get_long("domain", -1);
    if (domain < 0 || domain > kMaxDomain) throw InputError("option --domain: must be 0..232");
    run = args.get_or("run-id", run);
    duration = args.get_double("duration", duration);
    if (!(duration > 0)) throw InputError("option --duration: must be positive");
    security = args.get_or("security", "");
    identity = args.get_or("identity", "");
    name = args.get_or("name", name);
    if (name.empty()) throw InputError("option --name: must not be empty");
    user_data = args.get_or("user-data", "");
    if (security.empty() != identity.empty())
      throw InputError("options --security and --identity go together");
  } catch (const InputError& e) {
    std::cerr << "tessera-dds-snoop: error: " << e.what() << "\n";
    return 2;
  }

  Snoop s;
  ParticipantListener plistener(s.counts);
  fdds::DomainParticipantQos pq;
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  factory->get_default_participant_qos(pq);
  pq.name(name.c_str());
  pq.user_data().data_vec(
      std::vector<eprosima::fastrtps::rtps::octet>(user_data.begin(), user_data.end()));
  try {
    if (!security.empty())
      for (const auto& [k, v] : security_properties(security_files(security, identity)))
        pq.properties().properties().emplace_back(k, v);
  } catch (const InputError& e) {
    std::cerr << "tessera-dds-snoop: error: " << e.what() << "\n";
    return 2;
  }
  s.participant = create_participant_with_discovery_port(static_cast<int>(domain), pq, &plistener,
                                                         fdds::StatusMask::none(),
                                                         local_discovery_participants(0));
  if (!s.participant) {
    std::cerr << "tessera-dds-snoop: error: cannot create a participant on domain " << domain
              << "\n";
    return 1;
  }
  fdds::SubscriberQos sq = fdds::SUBSCRIBER_QOS_DEFAULT;
  sq.partition().push_back(run.c_str());
  s.subscriber = s.participant->create_subscriber(sq);
  if (s.subscriber) {
    s.watch<wire::AgentAnnouncementPubSubType, wire::AgentAnnouncement>(kAnnounceTopic);
    s.watch<wire::PartitionAssignmentPubSubType, wire::PartitionAssignment>(kAssignmentTopic);
    s.watch<wire::MeasurementHandoffPubSubType, wire::MeasurementHandoff>(kHandoffTopic);
    s.watch<wire::PoseBlockPubSubType, wire::PoseBlock>(kBlockTopic);
    s.watch<wire::RoundStatusPubSubType, wire::RoundStatus>(kStatusTopic);
    s.watch<wire::AgentReportPubSubType, wire::AgentReport>(kReportTopic);
    s.watch<wire::FinalEstimatePubSubType, wire::FinalEstimate>(kFinalTopic);
    s.watch<wire::ControlPubSubType, wire::Control>(kControlTopic);
  }
  std::printf("listening\n");
  std::fflush(stdout);

  std::mutex m;
  std::condition_variable cv;
  bool stop = false;
  signals.start([&](int) {
    std::lock_guard<std::mutex> lock(m);
    stop = true;
    cv.notify_all();
  });
  {
    std::unique_lock<std::mutex> lock(m);
    cv.wait_for(lock, std::chrono::duration<double>(duration), [&] { return stop; });
  }
  signals.stop();
  s.participant->delete_contained_entities();
  factory->delete_participant(s.participant);

  long total = 0;
  std::string detail;
  for (const auto& [topic, n] : s.counts.per_topic) {
    total += n;
    detail += " " + topic + "=" + std::to_string(n);
  }
  std::string refused;
  for (const auto& r : s.refused) refused += (refused.empty() ? "" : ",") + r;
  std::printf("participants=%ld readers=%d refused=%zu samples=%ld%s%s\n", s.counts.participants,
              s.readers, s.refused.size(), total, detail.c_str(),
              refused.empty() ? "" : (" refused_topics=" + refused).c_str());
  return 0;
}
