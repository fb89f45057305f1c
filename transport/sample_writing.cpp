#include "transport/sample_writing.hpp"

#include <fastdds/rtps/common/InstanceHandle.h>

#include <chrono>
#include <cstdio>

#include "transport/transport_error.hpp"

namespace tessera::transport {

namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

SampleWriter::SampleWriter(const DdsEntities& entities, const SessionOptions& options,
                           bool coordinator, const DdsTrace& trace)
    : entities_(entities), opt_(options), coordinator_(coordinator), trace_(trace) {}

void SampleWriter::write_raw(const std::string& name, void* sample, std::size_t size,
                             double timeout_s) {
  eprosima::fastdds::dds::DataWriter* w = entities_.writer(name);
  if (!w)
    throw TransportError("this " + std::string(coordinator_ ? "coordinator" : "agent") +
                         " does not write " + name);
  // Only writers whose readers are VOLATILE drop: the others keep their samples for late joiners.
  if (!entities_.readers_volatile(name)) {
    write_retrying(*w, name, sample, size, timeout_s);
    return;
  }
  drop_of(name).write(*w, [&] {
    write_retrying(*w, name, sample, size, timeout_s);
    return true;  // write_retrying throws when the sample does not go out
  });
}

void SampleWriter::write_retrying(eprosima::fastdds::dds::DataWriter& w, const std::string& name,
                                  void* sample, std::size_t size, double timeout_s) {
  const double bound_s = timeout_s > 0 ? timeout_s : opt_.write_timeout_s;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(Seconds(bound_s));
  for (;;) {
    // The handle overload reports why a write failed (the plain one only returns a bool).
    ReturnCode_t rc = w.write(sample, rtps::c_InstanceHandle_Unknown);
    if (rc == ReturnCode_t::RETCODE_OK) {
      bytes_ += size;
      ++messages_;
      return;
    }
    if (rc == ReturnCode_t::RETCODE_BAD_PARAMETER || rc == ReturnCode_t::RETCODE_NOT_ENABLED ||
        rc == ReturnCode_t::RETCODE_PRECONDITION_NOT_MET ||
        rc == ReturnCode_t::RETCODE_ILLEGAL_OPERATION)
      throw TransportError("DDS write on " + name + " failed (return code " + std::to_string(rc()) +
                           ")");
    // Most likely the bounded history is full of unacknowledged samples (2.9 reports that
    // as OUT_OF_RESOURCES, TIMEOUT or ERROR): wait for acknowledgements (not a busy loop),
    // then try again, until the deadline.
    ++retries_;
    trace_("write on %s: history full (return code %u), waiting for acknowledgements", name.c_str(),
           rc());
    if (std::chrono::steady_clock::now() > deadline) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%g s (return code %u)", bound_s, rc());
      throw TransportError("could not send on " + name + " within " + buf +
                           ": the receivers do not acknowledge (history full)");
    }
    w.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 20000000));
  }
}

AcknowledgedDrop& SampleWriter::drop_of(const std::string& name) {
  std::lock_guard<std::mutex> lock(drops_mutex_);
  std::unique_ptr<AcknowledgedDrop>& d = drops_[name];
  if (!d) d = std::make_unique<AcknowledgedDrop>();
  return *d;
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

bool SampleWriter::wait_acknowledged(const std::string& topic, Seconds timeout) {
  eprosima::fastdds::dds::DataWriter* w = entities_.writer(topic);
  if (timeout.count() <= 0 || !w) return false;
  return w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(timeout.count())) ==
         ReturnCode_t::RETCODE_OK;
}

}  // namespace tessera::transport
