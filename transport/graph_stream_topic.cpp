#include "transport/graph_stream_topic.hpp"

#include <chrono>
#include <condition_variable>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <mutex>
#include <stdexcept>
#include <tessera/util/input_error.hpp>

#include "tesseraPubSubTypes.h"
#include "transport/fastdds/discovery_port.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/qos.hpp"
#include "transport/run_identity.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::Duration_t;

namespace {

// Generous limits instead of Fast DDS's defaults (10 instances, 400 samples each): a mission
// has tens of robots and thousands of batches per robot, all kept for late readers.
constexpr std::int32_t kMaxRobots = 256;
constexpr std::int32_t kMaxBatchesPerRobot = 100000;

void stream_limits(dds::ResourceLimitsQosPolicy& r) {
  r.max_instances = kMaxRobots;
  r.max_samples_per_instance = kMaxBatchesPerRobot;
  r.max_samples = kMaxRobots * kMaxBatchesPerRobot;
  r.allocated_samples = 16;
}

// One participant with one topic of the stream type: shared set-up of writer and reader.
struct StreamParticipant {
  dds::DomainParticipant* participant = nullptr;
  dds::Topic* topic = nullptr;
  dds::TypeSupport type{new wire::GraphStreamBatchPubSubType()};

  StreamParticipant(int domain, const std::string& run_id, const std::string& role) {
    validate_run_id(run_id);
    dds::DomainParticipantQos pq = dds::PARTICIPANT_QOS_DEFAULT;
    // Not "tessera:<run>:..." (participant_name): a run's processes must not take the stream's
    // participants for peers of their run.
    pq.name("tessera-stream:" + run_id + ":" + role);
    udp_transport_only(pq);  // processes come and go: no shared memory (qos.hpp)
    watch_fastdds_log();     // names a stuck shared-memory listener (fastdds/shm_receive_watch.hpp)
    participant = create_participant_with_discovery_port(
        domain, pq, nullptr, dds::StatusMask::all(), local_discovery_participants(0));
    if (!participant)
      throw std::runtime_error("graph stream: cannot create a DDS participant on domain " +
                               std::to_string(domain));
    type.register_type(participant);
    topic =
        participant->create_topic(kGraphStreamTopic, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    if (!topic) throw std::runtime_error("graph stream: cannot create the topic");
  }
  ~StreamParticipant() {
    if (participant) {
      participant->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    }
  }
};

wire::GraphStreamBatch to_wire(const StreamBatch& b, int d, bool last, const std::string& run) {
  wire::GraphStreamBatch w;
  w.run_id(run);
  w.robot(b.robot);
  w.batch(b.sequence);
  w.dim(static_cast<std::uint32_t>(d));
  w.stamp(b.stamp);
  w.last(last);
  auto put_pose = [](std::vector<double>& out, const Pose& p) {
    out.insert(out.end(), p.R.data(), p.R.data() + p.R.size());
    out.insert(out.end(), p.t.data(), p.t.data() + p.t.size());
  };
  for (const StreamPose& p : b.poses) {
    w.pose_index().push_back(p.key.index);
    w.pose_stamp().push_back(p.stamp);
    put_pose(w.pose_guess(), p.guess);
  }
  for (const StreamMeasurement& m : b.measurements) {
    w.meas_from_robot().push_back(m.from.robot);
    w.meas_from_index().push_back(m.from.index);
    w.meas_to_robot().push_back(m.to.robot);
    w.meas_to_index().push_back(m.to.index);
    w.meas_kind().push_back(static_cast<std::uint8_t>(m.kind));
    w.meas_stamp().push_back(m.stamp);
    put_pose(w.meas_relative(), m.relative);
    w.meas_kappa().push_back(m.kappa);
    w.meas_tau().push_back(m.tau);
  }
  return w;
}

ReceivedStreamBatch from_wire(const wire::GraphStreamBatch& w) {
  ReceivedStreamBatch out;
  const std::string where = std::string(kGraphStreamTopic) + ": robot " +
                            std::to_string(w.robot()) + " batch " + std::to_string(w.batch());
  const int d = static_cast<int>(w.dim());
  if (d != 2 && d != 3) throw InputError(where + ": dim must be 2 or 3");
  const std::size_t pose_size = static_cast<std::size_t>(d * (d + 1));
  const std::size_t np = w.pose_index().size(), nm = w.meas_from_robot().size();
  if (w.pose_stamp().size() != np || w.pose_guess().size() != np * pose_size)
    throw InputError(where +
                     ": pose arrays of different lengths (pose_guess needs d*(d+1) "
                     "values per pose)");
  if (w.meas_from_index().size() != nm || w.meas_to_robot().size() != nm ||
      w.meas_to_index().size() != nm || w.meas_kind().size() != nm || w.meas_stamp().size() != nm ||
      w.meas_relative().size() != nm * pose_size || w.meas_kappa().size() != nm ||
      w.meas_tau().size() != nm)
    throw InputError(where +
                     ": measurement arrays of different lengths (meas_relative needs "
                     "d*(d+1) values per measurement)");
  auto get_pose = [&](const std::vector<double>& v, std::size_t k) {
    Pose p = Pose::identity(d);
    const double* x = v.data() + k * pose_size;
    for (int c = 0; c < d; ++c)
      for (int r = 0; r < d; ++r) p.R(r, c) = x[c * d + r];
    for (int r = 0; r < d; ++r) p.t(r) = x[d * d + r];
    return p;
  };
  out.dim = d;
  out.last = w.last();
  StreamBatch& b = out.batch;
  b.robot = w.robot();
  b.sequence = w.batch();
  b.stamp = w.stamp();
  for (std::size_t k = 0; k < np; ++k)
    b.poses.push_back(
        StreamPose{{w.robot(), w.pose_index()[k]}, w.pose_stamp()[k], get_pose(w.pose_guess(), k)});
  for (std::size_t k = 0; k < nm; ++k) {
    if (w.meas_kind()[k] > 2)
      throw InputError(where + ": measurement " + std::to_string(k) + " has kind " +
                       std::to_string(w.meas_kind()[k]) + " (0, 1 or 2)");
    StreamMeasurement m;
    m.from = {w.meas_from_robot()[k], w.meas_from_index()[k]};
    m.to = {w.meas_to_robot()[k], w.meas_to_index()[k]};
    m.kind = static_cast<MeasurementKind>(w.meas_kind()[k]);
    m.stamp = w.meas_stamp()[k];
    m.relative = get_pose(w.meas_relative(), k);
    m.kappa = w.meas_kappa()[k];
    m.tau = w.meas_tau()[k];
    b.measurements.push_back(std::move(m));
  }
  return out;
}

}  // namespace

struct GraphStreamWriter::Impl {
  StreamParticipant p;
  std::string run_id;
  dds::Publisher* publisher = nullptr;
  dds::DataWriter* writer = nullptr;

  Impl(int domain, const std::string& run) : p(domain, run, "writer"), run_id(run) {
    publisher = p.participant->create_publisher(publisher_qos(run_id));
    dds::DataWriterQos q = dds::DATAWRITER_QOS_DEFAULT;
    q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    q.reliability().max_blocking_time = Duration_t(5, 0);
    q.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    q.history().kind = dds::KEEP_ALL_HISTORY_QOS;
    stream_limits(q.resource_limits());
    q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    writer = publisher ? publisher->create_datawriter(p.topic, q) : nullptr;
    if (!writer) throw std::runtime_error("graph stream: cannot create the writer");
  }
};

GraphStreamWriter::GraphStreamWriter(int domain, const std::string& run_id)
    : impl_(std::make_unique<Impl>(domain, run_id)) {}
GraphStreamWriter::~GraphStreamWriter() = default;

void GraphStreamWriter::publish(const StreamBatch& batch, int d, bool last) {
  wire::GraphStreamBatch w = to_wire(batch, d, last, impl_->run_id);
  if (!impl_->writer->write(&w))
    throw std::runtime_error("graph stream: write of robot " + std::to_string(batch.robot) +
                             " batch " + std::to_string(batch.sequence) + " failed");
}

int GraphStreamWriter::matched_readers() const {
  dds::PublicationMatchedStatus s;
  impl_->writer->get_publication_matched_status(s);
  return s.current_count;
}

bool GraphStreamWriter::wait_acknowledged(double timeout_s) {
  return impl_->writer->wait_for_acknowledgments(Duration_t(timeout_s)) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
}

struct GraphStreamReader::Impl : public dds::DataReaderListener {
  StreamParticipant p;
  std::string run_id;
  std::optional<std::uint32_t> robot;
  dds::Subscriber* subscriber = nullptr;
  dds::DataReader* reader = nullptr;
  std::mutex mutex;
  std::condition_variable cv;
  bool available = false;

  Impl(int domain, const std::string& run, std::optional<std::uint32_t> only)
      : p(domain, run, only ? "reader-" + std::to_string(*only) : "reader"),
        run_id(run),
        robot(only) {
    subscriber = p.participant->create_subscriber(subscriber_qos(run_id));
    dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    q.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    q.history().kind = dds::KEEP_ALL_HISTORY_QOS;
    stream_limits(q.resource_limits());
    q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    reader = subscriber ? subscriber->create_datareader(p.topic, q, this) : nullptr;
    if (!reader) throw std::runtime_error("graph stream: cannot create the reader");
  }
  ~Impl() override {
    // The listener must not be called while this object goes away.
    if (reader) reader->set_listener(nullptr);
  }
  void on_data_available(dds::DataReader*) override {
    std::lock_guard<std::mutex> lock(mutex);
    available = true;
    cv.notify_all();
  }
};

GraphStreamReader::GraphStreamReader(int domain, const std::string& run_id,
                                     std::optional<std::uint32_t> robot)
    : impl_(std::make_unique<Impl>(domain, run_id, robot)) {}
GraphStreamReader::~GraphStreamReader() = default;

std::vector<ReceivedStreamBatch> GraphStreamReader::take(double timeout_s) {
  {
    std::unique_lock<std::mutex> lock(impl_->mutex);
    impl_->cv.wait_for(lock, std::chrono::duration<double>(timeout_s),
                       [&] { return impl_->available; });
    impl_->available = false;
  }
  std::vector<ReceivedStreamBatch> out;
  wire::GraphStreamBatch w;
  dds::SampleInfo info;
  while (impl_->reader->take_next_sample(&w, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data || w.run_id() != impl_->run_id) continue;
    if (impl_->robot && w.robot() != *impl_->robot) continue;
    out.push_back(from_wire(w));
  }
  return out;
}

}  // namespace tessera::transport
