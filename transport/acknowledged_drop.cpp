#include "transport/acknowledged_drop.hpp"

#include <cstddef>
#include <fastdds/dds/publisher/DataWriter.hpp>

namespace tessera::transport {

using eprosima::fastrtps::types::ReturnCode_t;

void AcknowledgedDrop::drop_if_due(eprosima::fastdds::dds::DataWriter& w) {
  if (writes_since_drop_ < kDropAcknowledgedEvery) return;
  if (w.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 0)) != ReturnCode_t::RETCODE_OK)
    return;
  std::size_t removed = 0;
  if (w.clear_history(&removed) == ReturnCode_t::RETCODE_OK) writes_since_drop_ = 0;
}

}  // namespace tessera::transport
