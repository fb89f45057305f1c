#include "transport/sample_writing.hpp"

#include <fastdds/rtps/common/InstanceHandle.h>

#include <chrono>
#include <cstdio>

#include "transport/transport_error.hpp"

namespace tessera::transport {

namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

thread_local bool SampleWriter::active_ = false;

SampleWriter::SampleWriter(const DdsEntities& entities, const SessionOptions& options,
                           bool coordinator, const DdsTrace& trace, Mailroom& room)
    : entities_(entities), opt_(options), coordinator_(coordinator), trace_(trace), room_(room) {}

namespace {

// The writer of `name`; throws TransportError when this process has none.
eprosima::fastdds::dds::DataWriter* writer_of(const DdsEntities& entities, const std::string& name,
                                              bool coordinator) {
  eprosima::fastdds::dds::DataWriter* w = entities.writer(name);
  if (!w)
    throw TransportError("this " + std::string(coordinator ? "coordinator" : "agent") +
                         " does not write " + name);
  return w;
}

}  // namespace

bool SampleWriter::try_write_raw(const std::string& name, void* sample, std::size_t size,
                                 unsigned* failure) {
  eprosima::fastdds::dds::DataWriter* w = writer_of(entities_, name, coordinator_);
  // The handle overload reports why a write failed (the plain one only returns a bool).
  ReturnCode_t rc = w->write(sample, rtps::c_InstanceHandle_Unknown);
  if (rc == ReturnCode_t::RETCODE_OK) {
    bytes_ += size;
    ++messages_;
    return true;
  }
  if (rc == ReturnCode_t::RETCODE_BAD_PARAMETER || rc == ReturnCode_t::RETCODE_NOT_ENABLED ||
      rc == ReturnCode_t::RETCODE_PRECONDITION_NOT_MET ||
      rc == ReturnCode_t::RETCODE_ILLEGAL_OPERATION)
    throw TransportError("DDS write on " + name + " failed (return code " + std::to_string(rc()) +
                         ")");
  // Most likely the bounded history is full of unacknowledged samples (2.9 reports that as
  // OUT_OF_RESOURCES, TIMEOUT or ERROR).
  ++retries_;
  trace_("write on %s: history full (return code %u)", name.c_str(), rc());
  if (failure) *failure = rc();
  return false;
}

void SampleWriter::defer_locked(std::function<void()> write) {
  backlog_.push_back(std::move(write));
  if (backlogged_.load()) return;
  room_.with_lock([&] { return backlogged_ = true; });
  room_.notify();
}

void SampleWriter::flush_backlog() {
  if (!backlogged_.load()) return;
  std::lock_guard<std::mutex> one(flush_mutex_);
  for (;;) {
    std::function<void()> next;
    {
      std::lock_guard<std::mutex> lock(backlog_mutex_);
      if (backlog_.empty()) {
        flushing_ = false;
        room_.with_lock([&] { return backlogged_ = false; });
        return;
      }
      next = std::move(backlog_.front());
      backlog_.pop_front();
      flushing_ = true;
    }
    try {
      next();  // waits for acknowledgements as any write outside a NoWait scope
    } catch (...) {
      std::lock_guard<std::mutex> lock(backlog_mutex_);
      flushing_ = false;
      throw;
    }
  }
}

void SampleWriter::write_raw(const std::string& name, void* sample, std::size_t size) {
  eprosima::fastdds::dds::DataWriter* w = writer_of(entities_, name, coordinator_);
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::duration_cast<std::chrono::nanoseconds>(Seconds(opt_.write_timeout_s));
  for (;;) {
    unsigned rc = 0;
    if (try_write_raw(name, sample, size, &rc)) return;
    // Wait for acknowledgements (not a busy loop), then try again, until the deadline.
    if (std::chrono::steady_clock::now() > deadline) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%g s (return code %u)", opt_.write_timeout_s, rc);
      throw TransportError("could not send on " + name + " within " + buf +
                           ": the receivers do not acknowledge (history full)");
    }
    w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 20000000));
  }
}

void SampleWriter::flush(Seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
  for (auto& [name, w] : entities_.writers()) {
    (void)name;
    double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return;
    w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(left));
  }
}

void SampleWriter::wait_acknowledged(const std::string& topic, Seconds timeout) {
  eprosima::fastdds::dds::DataWriter* w = entities_.writer(topic);
  if (timeout.count() > 0 && w)
    w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(timeout.count()));
}

}  // namespace tessera::transport
