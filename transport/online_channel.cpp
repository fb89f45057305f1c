#include "transport/online_channel.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <mutex>
#include <set>
#include <stdexcept>

#include "tesseraPubSubTypes.h"
#include "transport/acknowledged_drop.hpp"
#include "transport/fastdds/discovery_port.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/message_mapping.hpp"
#include "transport/network_profile.hpp"
#include "transport/qos.hpp"
#include "transport/run_identity.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::Duration_t;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {
// Reports kept per agent for joiners: one per epoch boundary.
constexpr std::int32_t kReportHistory = 100000;

// OnlineStepCoarse's numbers (idl/tessera.idl): 0 none, 1 blocks, 2 smoothed.
std::uint32_t wire_of_coarse(NewtonRefineOptions::Coarse c) {
  return c == NewtonRefineOptions::Coarse::kBlocks     ? 1u
         : c == NewtonRefineOptions::Coarse::kSmoothed ? 2u
                                                       : 0u;
}
NewtonRefineOptions::Coarse coarse_of_wire(std::uint32_t v) {
  return v == 1u   ? NewtonRefineOptions::Coarse::kBlocks
         : v == 2u ? NewtonRefineOptions::Coarse::kSmoothed
                   : NewtonRefineOptions::Coarse::kNone;
}
}  // namespace

// A reliable write that finds the bounded history full of samples some reader has not
// acknowledged yet (a slow peer) waits for acknowledgements and tries again, up to a minute,
// instead of failing the run.
template <class Sample>
bool write_patiently(dds::DataWriter* writer, Sample& sample) {
  for (int attempt = 0; attempt < 600; ++attempt) {
    if (writer->write(&sample)) return true;
    writer->wait_for_acknowledgments(Duration_t(0, 100000000));
  }
  return false;
}

struct OnlineChannel::Impl : public dds::DataReaderListener {
  std::string run_id;
  std::uint32_t agent;
  OnlineTeamOptions team;  // this agent's, written into every report it sends
  dds::DomainParticipant* participant = nullptr;
  dds::Publisher* publisher = nullptr;
  dds::Subscriber* subscriber = nullptr;
  dds::TypeSupport block_type{new wire::PoseBlockPubSubType()};
  dds::TypeSupport status_type{new wire::RoundStatusPubSubType()};
  dds::TypeSupport report_type{new wire::OnlineReportPubSubType()};
  dds::TypeSupport estimate_type{new wire::FinalEstimatePubSubType()};
  dds::DataWriter* estimate_writer = nullptr;
  // Their readers are VOLATILE: they drop their acknowledged samples (acknowledged_drop.hpp)
  // instead of keeping their last kVolatileWriterHistory for the whole mission.
  dds::DataWriter *block_writer = nullptr, *status_writer = nullptr;
  AcknowledgedDrop block_drop, status_drop;
  dds::DataWriter* report_writer = nullptr;
  dds::DataReader *block_reader = nullptr, *status_reader = nullptr, *report_reader = nullptr;
  std::mutex mutex;
  std::condition_variable cv;
  bool available = false;
  std::set<std::uint32_t> lost;  // agents whose participant left or was dropped

  // Liveliness of the other agents: their participants' names say which agent they are. A
  // waiting agent is woken, so a take-over does not wait for a timeout.
  struct Discovery : public dds::DomainParticipantListener {
    Impl* impl = nullptr;
    void on_participant_discovery(
        dds::DomainParticipant*,
        eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
      using Info = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
      const bool gone =
          info.status == Info::REMOVED_PARTICIPANT || info.status == Info::DROPPED_PARTICIPANT;
      if (!gone && info.status != Info::DISCOVERED_PARTICIPANT) return;
      const auto id =
          parse_online_participant_name(info.info.m_participantName.to_string(), impl->run_id);
      if (!id) return;
      std::lock_guard<std::mutex> lock(impl->mutex);
      // A participant of that agent discovered again (a process started again, or a live one
      // the lease dropped) is not lost any more.
      if (gone)
        impl->lost.insert(*id);
      else
        impl->lost.erase(*id);
      impl->available = true;
      impl->cv.notify_all();
    }
  } discovery;

  Impl(int domain, const std::string& run, std::uint32_t me, std::uint32_t agents, double lease_s)
      : run_id(run), agent(me) {
    validate_run_id(run_id);
    dds::DomainParticipantQos pq = dds::PARTICIPANT_QOS_DEFAULT;
    pq.name(online_participant_name(run_id, me));
    // A killed agent's readers stay matched until its participant lease expires, and writes
    // to them wait for acknowledgements meanwhile: Fast DDS's default lease (20 s) would hold
    // the survivors that long before their report wait can name the silent agent.
    pq.wire_protocol().builtin.discovery_config.leaseDuration = Duration_t(lease_s);
    pq.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod =
        Duration_t(lease_s / 5.0);
    discovery.impl = this;
    udp_transport_only(pq);  // processes come and go: no shared memory (qos.hpp)
    watch_fastdds_log();     // names a stuck shared-memory listener (fastdds/shm_receive_watch.hpp)
    participant = create_participant_with_discovery_port(
        domain, pq, &discovery, dds::StatusMask::none(), local_discovery_participants(agents));
    if (!participant)
      throw std::runtime_error("online channel: cannot create a DDS participant on domain " +
                               std::to_string(domain));
    block_type.register_type(participant);
    status_type.register_type(participant);
    report_type.register_type(participant);
    estimate_type.register_type(participant);
    publisher = participant->create_publisher(publisher_qos(run_id));
    subscriber = participant->create_subscriber(subscriber_qos(run_id));
    if (!publisher || !subscriber)
      throw std::runtime_error("online channel: cannot create a publisher or subscriber");
    const NetworkProfile net;
    auto endpoints = [&](const char* name, dds::TypeSupport& type, bool transient,
                         dds::DataWriter*& writer, dds::DataReader*& reader) {
      dds::Topic* topic =
          participant->create_topic(name, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
      if (!topic) throw std::runtime_error(std::string("online channel: cannot create ") + name);
      dds::DataWriterQos wq = writer_qos(transient, 10.0, agents, net, false);
      wq.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
      dds::DataReaderQos rq = reader_qos(transient, 10.0, agents, net, false);
      rq.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
      if (transient) {
        // Every report of the run stays with its writer (acknowledged or not): a joiner
        // follows the epochs it missed from them.
        wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
        wq.history().depth = kReportHistory;
        wq.resource_limits().max_samples = kReportHistory;
        wq.resource_limits().max_samples_per_instance = kReportHistory;
        rq.history().kind = dds::KEEP_ALL_HISTORY_QOS;
        rq.resource_limits().max_samples = kReportHistory;
        rq.resource_limits().max_samples_per_instance = kReportHistory;
      }
      writer = publisher->create_datawriter(topic, wq);
      reader = subscriber->create_datareader(topic, rq, this);
      if (!writer || !reader)
        throw std::runtime_error(std::string("online channel: cannot create endpoints of ") + name);
    };
    endpoints(kOnlineBlockTopic, block_type, false, block_writer, block_reader);
    endpoints(kOnlineStatusTopic, status_type, false, status_writer, status_reader);
    // Reports are kept for readers that match later: the first epoch's reports may be sent
    // before every agent's reader is discovered.
    endpoints(kOnlineReportTopic, report_type, true, report_writer, report_reader);
    // Estimates: for whoever listens (a monitor, the robots); the newest per robot matters.
    dds::Topic* estimates = participant->create_topic(
        kOnlineEstimateTopic, estimate_type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    dds::DataWriterQos eq = dds::DATAWRITER_QOS_DEFAULT;
    eq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    eq.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    eq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    // The newest of every robot this agent publishes (its own, and robots whose lost agents'
    // blocks it adopted) stays for late readers.
    eq.history().depth = static_cast<std::int32_t>(std::max<std::uint32_t>(1, agents));
    eq.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    estimate_writer = estimates ? publisher->create_datawriter(estimates, eq) : nullptr;
    if (!estimate_writer)
      throw std::runtime_error("online channel: cannot create the estimate writer");
  }
  ~Impl() override {
    for (auto* r : {block_reader, status_reader, report_reader})
      if (r) r->set_listener(nullptr);
    if (participant) {
      participant->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    }
  }
  // Samples are taken here, as they arrive, into the buffers the agent's loop empties: a
  // reader whose bounded history filled while its agent computed (or waited in a write of
  // its own) would stop acknowledging, and two agents doing that to each other would block
  // each other's writes for good.
  void on_data_available(dds::DataReader* reader) override {
    std::lock_guard<std::mutex> lock(mutex);
    try {
      if (reader == report_reader) {
        take_reports_locked();
      } else if (reader == block_reader) {
        wire::PoseBlock w;
        dds::SampleInfo info;
        while (block_reader->take_next_sample(&w, &info) == ReturnCode_t::RETCODE_OK)
          if (info.valid_data && w.run_id() == run_id)
            messages.push_back(
                {w.epoch(), w.sender(), w.broadcast(), w.recipients(), from_wire(w)});
      } else if (reader == status_reader) {
        wire::RoundStatus w;
        dds::SampleInfo info;
        while (status_reader->take_next_sample(&w, &info) == ReturnCode_t::RETCODE_OK)
          if (info.valid_data && w.run_id() == run_id)
            messages.push_back(
                {w.epoch(), w.sender(), w.broadcast(), w.recipients(), from_wire(w)});
      }
    } catch (const std::exception& e) {
      if (error.empty()) error = e.what();
    }
    available = true;
    cv.notify_all();
  }

  void take_reports_locked() {
    wire::OnlineReport w;
    dds::SampleInfo info;
    while (report_reader->take_next_sample(&w, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || w.run_id() != run_id) continue;
      if (w.held_robot().size() != w.held_count().size())
        throw TransportError("online report of agent " + std::to_string(w.sender()) +
                             ": held arrays of different lengths");
      OnlineReportSample r;
      r.epoch = w.epoch();
      r.sender = w.sender();
      for (std::size_t k = 0; k < w.held_robot().size(); ++k)
        r.held[w.held_robot()[k]] = w.held_count()[k];
      r.converged = w.converged();
      r.rank = static_cast<int>(w.rank());
      r.dim = static_cast<int>(w.dim());
      r.pose_ids = w.pose_ids();
      r.data = w.data();
      r.next_members = w.next_members();
      r.certify = w.certify();
      r.lost = w.lost();
      r.at_epoch = w.at_epoch();
      const wire::OnlineRebalance& b = w.rebalance();
      RebalanceOptions& rb = r.team.rebalance;
      rb.enabled = b.enabled();
      rb.slack = b.slack();
      rb.min_excess = static_cast<std::size_t>(b.min_excess());
      rb.cut_fraction = b.cut_fraction();
      rb.max_passes = static_cast<int>(b.max_passes());
      rb.pass_patience = static_cast<std::size_t>(b.pass_patience());
      rb.place_by_links = b.place_by_links();
      r.team.step_coarse = coarse_of_wire(w.step_coarse().coarse());
      r.team.step_coarse_min_blocks = static_cast<int>(w.step_coarse().min_blocks());
      r.team.step_coarse_aggregates = static_cast<int>(w.step_coarse().aggregates());
      r.team.run_wide.first_step_on_grown_factors = w.first_step_grown_factors();
      r.team.run_wide.tangent_split_dots = !w.tangent_sequential_dots();
      r.team.run_wide.local_rounds = !w.no_local_rounds();
      r.team.run_wide.local_threshold = w.local_threshold();
      r.team.run_wide.refactor_growth = w.refactor_growth();
      reports.push_back(std::move(r));
    }
  }

  std::vector<OnlineReportSample> reports;
  std::vector<OnlineProtocolSample> messages;
  std::string error;
};

OnlineChannel::OnlineChannel(int domain, const std::string& run_id, std::uint32_t agent,
                             std::uint32_t agents, double lease_s, const OnlineTeamOptions& team)
    : impl_(std::make_unique<Impl>(domain, run_id, agent, agents, lease_s)) {
  impl_->team = team;
}
OnlineChannel::~OnlineChannel() = default;

std::size_t OnlineChannel::send(const OutgoingMessage& m, std::uint32_t epoch) {
  if (const auto* block = std::get_if<PoseBlockMessage>(&m.message)) {
    wire::PoseBlock w = to_wire_block(*block, impl_->run_id, m.broadcast, m.recipients);
    w.epoch(epoch);
    if (!impl_->block_drop.write(*impl_->block_writer,
                                 [&] { return write_patiently(impl_->block_writer, w); }))
      throw std::runtime_error("online channel: a pose block write failed");
    return serialized_size(w);
  }
  wire::RoundStatus w = to_wire_status(std::get<RoundStatusMessage>(m.message), impl_->run_id,
                                       m.broadcast, m.recipients);
  w.epoch(epoch);
  if (!impl_->status_drop.write(*impl_->status_writer,
                                [&] { return write_patiently(impl_->status_writer, w); }))
    throw std::runtime_error("online channel: a round status write failed");
  return serialized_size(w);
}

std::size_t OnlineChannel::send_report(const OnlineReportSample& r) {
  wire::OnlineReport w;
  w.run_id(impl_->run_id);
  w.epoch(r.epoch);
  w.sender(r.sender);
  for (const auto& [robot, count] : r.held) {
    w.held_robot().push_back(robot);
    w.held_count().push_back(count);
  }
  w.converged(r.converged);
  w.rank(static_cast<std::uint32_t>(r.rank));
  w.dim(static_cast<std::uint32_t>(r.dim));
  w.pose_ids(r.pose_ids);
  w.data(r.data);
  w.next_members(r.next_members);
  w.certify(r.certify);
  w.lost(r.lost);
  w.at_epoch(r.at_epoch);
  const RebalanceOptions& own = impl_->team.rebalance;
  wire::OnlineRebalance& b = w.rebalance();
  b.enabled(own.enabled);
  b.slack(own.slack);
  b.min_excess(own.min_excess);
  b.cut_fraction(own.cut_fraction);
  b.max_passes(static_cast<std::uint32_t>(own.max_passes));
  b.pass_patience(own.pass_patience);
  b.place_by_links(own.place_by_links);
  w.step_coarse().coarse(wire_of_coarse(impl_->team.step_coarse));
  w.step_coarse().min_blocks(static_cast<std::uint32_t>(impl_->team.step_coarse_min_blocks));
  w.step_coarse().aggregates(static_cast<std::uint32_t>(impl_->team.step_coarse_aggregates));
  w.first_step_grown_factors(impl_->team.run_wide.first_step_on_grown_factors);
  w.tangent_sequential_dots(!impl_->team.run_wide.tangent_split_dots);
  w.no_local_rounds(!impl_->team.run_wide.local_rounds);
  w.local_threshold(impl_->team.run_wide.local_threshold);
  w.refactor_growth(impl_->team.run_wide.refactor_growth);
  if (!write_patiently(impl_->report_writer, w))
    throw std::runtime_error("online channel: a report write failed");
  return serialized_size(w);
}

void OnlineChannel::publish_estimate(std::uint32_t epoch, int d,
                                     const std::vector<std::uint64_t>& index,
                                     const std::vector<double>& poses, std::uint32_t robot) {
  wire::FinalEstimate w;
  w.run_id(impl_->run_id);
  w.sender(robot == kOwnRobot ? impl_->agent : robot);
  w.dim(static_cast<std::uint32_t>(d));
  w.epoch(epoch);
  for (std::uint64_t k : index) w.pose_ids().push_back(static_cast<std::uint32_t>(k));
  w.pose_data(poses);
  if (!write_patiently(impl_->estimate_writer, w))
    throw std::runtime_error("online channel: an estimate write failed");
}

bool OnlineChannel::wait(double timeout_s) {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  const bool got = impl_->cv.wait_for(lock, std::chrono::duration<double>(timeout_s),
                                      [&] { return impl_->available; });
  impl_->available = false;
  return got;
}

std::vector<OnlineReportSample> OnlineChannel::take_reports() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->error.empty()) throw TransportError(impl_->error);
  std::vector<OnlineReportSample> out;
  out.swap(impl_->reports);
  return out;
}

std::vector<OnlineProtocolSample> OnlineChannel::take_messages() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!impl_->error.empty()) throw TransportError(impl_->error);
  std::vector<OnlineProtocolSample> out;
  out.swap(impl_->messages);
  return out;
}

int OnlineChannel::matched_peers() const {
  int fewest = 1 << 30;
  for (auto* w : {impl_->block_writer, impl_->status_writer}) {
    dds::PublicationMatchedStatus s;
    w->get_publication_matched_status(s);
    fewest = std::min(fewest, s.current_count);
  }
  for (auto* r : {impl_->block_reader, impl_->status_reader}) {
    dds::SubscriptionMatchedStatus s;
    r->get_subscription_matched_status(s);
    fewest = std::min(fewest, s.current_count);
  }
  return fewest;
}

void OnlineChannel::flush(double timeout_s) {
  for (auto* w : {impl_->block_writer, impl_->status_writer, impl_->report_writer})
    w->wait_for_acknowledgments(Duration_t(timeout_s));
}

std::vector<std::uint32_t> OnlineChannel::lost_agents() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return {impl_->lost.begin(), impl_->lost.end()};
}

}  // namespace tessera::transport
