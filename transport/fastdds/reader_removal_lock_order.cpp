#include "transport/fastdds/reader_removal_lock_order.hpp"

namespace tessera::transport {

void keep_acknowledged_samples(eprosima::fastdds::dds::DataWriterQos& q) {
  q.durability().kind = eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS;
}

}  // namespace tessera::transport
