// A reader that leaves while the writer is still repairing samples for it must not hang the
// writer's process (Fast DDS 2.9.1's lock-order inversion between
// StatefulWriter::matched_reader_remove and the flow controller's thread; the cause and how it
// is avoided: transport/fastdds/reader_removal_lock_order.hpp).
//
// A writer process publishes pose blocks with the QoS of a per-round topic (transport's
// writer_qos). This process keeps one reader that takes everything (the survivors) and, cycle
// after cycle, creates 4 readers that never take (a one-sample history rejects the rest, so
// they NACK them and the writer keeps repairing) and deletes them 150 ms later. After each
// cycle the writer must go on publishing; a writer that stopped is replaced (and counted).
// Measured (seven runs of 100 cycles each way, load 11-20): with Fast DDS's VOLATILE writer
// (TESSERA_LOCK_ORDER_VOLATILE=1) the writer hung 2, 1, 3, 1, 3, 3 and 8 times, 21 in 700
// cycles (the gdb stacks of a run's first hang, TESSERA_TEARDOWN_STACKS=1: the inversion
// above); with writer_qos's writers 0 in 700. The environment variables below only serve such
// measurements. Domain 135.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "dds_process_support.hpp"
#include "tesseraPubSubTypes.h"
#include "transport/fastdds/shm_leftovers.hpp"
#include "transport/network_profile.hpp"
#include "transport/qos.hpp"

namespace {

namespace fdds = ::eprosima::fastdds::dds;
using namespace tessera::transport;
using ReturnCode_t = eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

constexpr int kDomain = 135;  // this test's own domain
const char* const kTopic = "tessera_lock_order_test";

// Cycles of leaving readers (TESSERA_LOCK_ORDER_CYCLES overrides, for measuring).
int cycles() {
  const char* env = std::getenv("TESSERA_LOCK_ORDER_CYCLES");
  return env ? std::atoi(env) : 100;
}

// The network profile (TESSERA_LOCK_ORDER_PROFILE overrides): "lossy" repairs at once and
// heartbeats every 10 ms, so the flow controller's thread repairs most of the time.
std::string profile() {
  const char* env = std::getenv("TESSERA_LOCK_ORDER_PROFILE");
  return env ? env : "lossy";
}

// Leaving readers per cycle (TESSERA_LOCK_ORDER_READERS overrides).
int leaving_per_cycle() {
  const char* env = std::getenv("TESSERA_LOCK_ORDER_READERS");
  return env ? std::atoi(env) : 4;
}

// Doubles per sample (TESSERA_LOCK_ORDER_DOUBLES overrides): blocks of a few hundred poses, so
// that sending a burst of repairs keeps the flow controller's thread busy for a while.
std::size_t sample_doubles() {
  const char* env = std::getenv("TESSERA_LOCK_ORDER_DOUBLES");
  return env ? static_cast<std::size_t>(std::atol(env)) : 2000;
}

volatile std::sig_atomic_t writer_stop = 0;
extern "C" void on_writer_term(int) {
  writer_stop = 1;
}

// The writer process (this test binary again, with kWriterRunEnv set to the run id): publishes
// blocks as fast as write() lets it until SIGTERM, then deletes its participant. Never returns.
const char* const kWriterRunEnv = "TESSERA_LOCK_ORDER_WRITER_RUN";

[[noreturn]] void writer_process(const std::string& run) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  const NetworkProfile net = network_profile(profile());
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipant* p = factory->create_participant(
      kDomain, participant_qos("lock-order-writer-" + run, 1.0, {}, kDomain, 2, net, {}, true, {}));
  if (!p) _exit(3);
  fdds::TypeSupport type(new tessera::wire::PoseBlockPubSubType());
  type.register_type(p);
  fdds::Topic* t = p->create_topic(kTopic, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::DataWriterQos q = writer_qos(false, 1.0, 2, net, false);
  // TESSERA_LOCK_ORDER_VOLATILE=1: Fast DDS's VOLATILE writer instead (shows the hang).
  if (const char* v = std::getenv("TESSERA_LOCK_ORDER_VOLATILE"); v && std::string(v) == "1")
    q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
  fdds::DataWriter* w = p->create_publisher(publisher_qos(run))->create_datawriter(t, q);
  if (!w) _exit(4);
  tessera::wire::PoseBlock s;
  s.run_id(run);
  s.data(std::vector<double>(sample_doubles(), 1.0));
  std::signal(SIGTERM, on_writer_term);
  for (std::uint32_t round = 0; !writer_stop; ++round) {
    s.round(round);
    w->write(&s);
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  p->delete_contained_entities();
  factory->delete_participant(p);
  _exit(0);
}

// Stops the writer process. Not by SIGKILL while it runs: its Fast DDS threads (the flow
// controller sending repairs) hold the readers' shared-memory port mutex while they write, and
// a process killed then leaves it locked; this process's participant then aborted when it was
// deleted ("Interprocess mutex timeout when locking", seen at the end of a run of 100 cycles).
// SIGTERM ends the writer between two writes and deletes its participant; SIGKILL only when
// it does not exit within 10 s (a hung writer).
void stop_writer(pid_t writer) {
  tessera::test::dds::Process p;
  p.pid = writer;
  kill(writer, SIGTERM);
  tessera::test::dds::wait_all({&p}, 10.0);
}

// Starts the writer process (a fresh exec: this process already has Fast DDS threads).
pid_t start_writer(const std::string& run) {
  const pid_t pid = fork();
  if (pid == 0) {
    setenv(kWriterRunEnv, run.c_str(), 1);
    const int null = open("/dev/null", O_WRONLY);  // gtest's lines of the child
    if (null >= 0) dup2(null, 1);
    const std::string filter = "--gtest_filter=DdsWriterLockOrder.*";
    char* argv[] = {const_cast<char*>("/proc/self/exe"), const_cast<char*>(filter.c_str()),
                    nullptr};
    execv(argv[0], argv);
    _exit(127);
  }
  return pid;
}

// The writer's threads, as gdb sees them (only when TESSERA_TEARDOWN_STACKS is set).
void print_stacks(pid_t pid) {
  if (!std::getenv("TESSERA_TEARDOWN_STACKS")) return;
  const std::string cmd = "gdb -p " + std::to_string(pid) +
                          " -batch -ex 'thread apply all bt' 2>/dev/null | grep -E '^#|^Thread'";
  std::fflush(stdout);
  (void)std::system(cmd.c_str());
}

// Samples read by `reader` so far are added to `*count`; true once it grew past `target`
// before `deadline`.
bool read_until(fdds::DataReader* reader, long* count, long target, Clock::time_point deadline) {
  tessera::wire::PoseBlock in;
  fdds::SampleInfo info;
  while (Clock::now() < deadline) {
    while (reader->take_next_sample(&in, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) ++*count;
    if (*count > target) return true;
    reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0.05));
  }
  return false;
}

// This process's side: a participant with the steady reader, and the leaving readers' QoS: one
// sample kept and never taken, so every later sample is rejected, NACKed and repaired while
// the reader is matched.
struct ReaderSide {
  ReaderSide(const std::string& run, const NetworkProfile& net, int generation) {
    p = factory()->create_participant(
        kDomain, participant_qos("lock-order-readers-" + run + "-" + std::to_string(generation),
                                 1.0, {}, kDomain, 2, net, {}, true, {}));
    if (!p) return;
    type.register_type(p);
    t = p->create_topic(kTopic, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    sub = p->create_subscriber(subscriber_qos(run));
    steady = sub->create_datareader(t, reader_qos(false, 1.0, 2, net, false));
    stuck = reader_qos(false, 1.0, 2, net, false);
    stuck.resource_limits().max_samples = 1;
    stuck.resource_limits().max_samples_per_instance = 1;
    stuck.resource_limits().allocated_samples = 1;
  }
  // A fresh participant after each writer process: a process SIGKILLed while writing into this
  // one's shared-memory port leaves that port locked (transport/qos.hpp, participant_qos).
  ~ReaderSide() {
    if (!p) return;
    p->delete_contained_entities();
    factory()->delete_participant(p);
  }
  static fdds::DomainParticipantFactory* factory() {
    return fdds::DomainParticipantFactory::get_instance();
  }
  fdds::DomainParticipant* p = nullptr;
  fdds::TypeSupport type{new tessera::wire::PoseBlockPubSubType()};
  fdds::Topic* t = nullptr;
  fdds::Subscriber* sub = nullptr;
  fdds::DataReader* steady = nullptr;
  fdds::DataReaderQos stuck;
};

TEST(DdsWriterLockOrder, ReaderLeavingWhileItsRepairsAreQueuedDoesNotHangTheWriter) {
  if (const char* run = std::getenv(kWriterRunEnv)) writer_process(run);
  const std::string run = "lock-order-" + std::to_string(getpid());
  const NetworkProfile net = network_profile(profile());
  // A hung writer process is SIGKILLed while it writes, so it can die holding a port's mutex:
  // an earlier run of this test (or one that crashed) may have left such a port of this domain
  // in /dev/shm, and a participant that gets the same port number then aborts on "Interprocess
  // mutex timeout when locking". Dead files go first, as before every `tessera launch`
  // (transport/fastdds/shm_leftovers.hpp).
  ShmCleanupOptions dead;
  dead.domain = kDomain;
  remove_dead_shm_files(dead);
  pid_t writer = start_writer(run);
  ASSERT_GT(writer, 0);
  int generation = 0;
  auto readers = std::make_unique<ReaderSide>(run, net, generation);
  ASSERT_NE(readers->steady, nullptr);
  long received = 0;
  ASSERT_TRUE(read_until(readers->steady, &received, 100, Clock::now() + std::chrono::seconds(30)))
      << "the writer process never reached the steady reader";

  const int n = cycles();
  int hangs = 0;
  for (int cycle = 0; cycle < n; ++cycle) {
    std::vector<fdds::DataReader*> leaving;
    for (int k = 0; k < leaving_per_cycle(); ++k) {
      leaving.push_back(readers->sub->create_datareader(readers->t, readers->stuck));
      ASSERT_NE(leaving.back(), nullptr);
    }
    // Matched, and a few heartbeat periods of repairs.
    const auto matched_by = Clock::now() + std::chrono::seconds(10);
    for (fdds::DataReader* r : leaving) {
      fdds::SubscriptionMatchedStatus status{};
      while (Clock::now() < matched_by) {
        r->get_subscription_matched_status(status);
        if (status.current_count > 0) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    for (fdds::DataReader* r : leaving)
      ASSERT_EQ(readers->sub->delete_datareader(r), ReturnCode_t::RETCODE_OK);
    // The writer goes on: the steady reader gets new samples.
    const long before = received;
    if (!read_until(readers->steady, &received, before + 20,
                    Clock::now() + std::chrono::seconds(10))) {
      ++hangs;
      std::printf("cycle %d: the writer process stopped publishing\n", cycle);
      if (hangs == 1) print_stacks(writer);
      kill(writer, SIGKILL);
      waitpid(writer, nullptr, 0);
      readers.reset();
      writer = start_writer(run);
      readers = std::make_unique<ReaderSide>(run, net, ++generation);
      ASSERT_NE(readers->steady, nullptr);
      ASSERT_TRUE(read_until(readers->steady, &received, received + 100,
                             Clock::now() + std::chrono::seconds(30)))
          << "the restarted writer process never reached the steady reader";
    }
  }
  std::printf("%d cycles of %d leaving readers: the writer process hung in %d\n", n,
              leaving_per_cycle(), hangs);
  EXPECT_EQ(hangs, 0);
  stop_writer(writer);
  readers.reset();
  remove_dead_shm_files(dead);  // a hung writer's ports, which it could not remove
}

}  // namespace
