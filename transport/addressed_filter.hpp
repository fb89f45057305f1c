#pragma once
// A Fast DDS content filter that passes only the samples addressed to one agent, read off the
// serialized payload without deserializing it. Readers of a shared topic then receive only
// their own samples: with it registered on the writer's participant too, Fast DDS filters on
// the writer's side and never sends the others' samples at all. Without it, every agent of a
// large run received and decoded every hand-off (the whole graph's measurements that change
// owner, N - 1 times over) and every addressed pose block of every round (docs/scale.md).
// Internal to transport/.

#include <cstddef>
#include <cstdint>

namespace eprosima::fastdds::dds {
class DomainParticipant;
}

namespace tessera::transport {

/// The largest serialized sample sent on a filtered topic. Fast DDS 2.9 cannot filter on the
/// writer's side a sample it sends in fragments ("Cannot add DATA_FRAG submsg"): samples up to
/// this size fit in one message of its transports (64 KB, less the RTPS headers and the
/// filter's inline QoS). Larger ones go on the unfiltered topics or in parts.
inline constexpr std::size_t kMaxAddressedSampleBytes = 60000;

/// The filter class name registered on every participant.
inline constexpr const char* kAddressedFilterClass = "TESSERA_ADDRESSED";

/// Which wire type's layout the filter reads (the filter expression names it).
enum class AddressedLayout {
  kHandoff,  ///< wire::MeasurementHandoff: run_id, sender, recipient (passes recipient == me)
  kBlock     ///< wire::PoseBlock: run_id, round, sender, phase, broadcast, recipients
             ///< (passes broadcast or me among recipients)
};

/// The filter expression of a layout ("handoff", "block").
const char* addressed_expression(AddressedLayout layout);

/// Whether the CDR payload `data` (`size` bytes, with its 4-byte encapsulation header) of a
/// sample of `layout` is addressed to `agent`. A payload too short or malformed to read passes,
/// so that the reader's own decoding reports it.
bool addressed_to_agent(AddressedLayout layout, const std::uint8_t* data, std::size_t size,
                        std::uint32_t agent);

/// Registers the filter factory on `participant` (idempotent per participant). Returns false
/// when Fast DDS refuses it.
bool register_addressed_filter(eprosima::fastdds::dds::DomainParticipant& participant);

}  // namespace tessera::transport
