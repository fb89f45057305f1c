#pragma once
// Conversions between core's transport-independent types (protocol messages, measurements,
// poses) and the generated DDS wire types (idl/tessera.idl). Mechanical, field by field;
// pose data as flat column-major arrays. Decoding checks array lengths and throws
// TransportError on a malformed message (never reads out of bounds).

#include <cstdint>
#include <string>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

#include "tessera.h"
#include "transport/transport_error.hpp"

namespace tessera::transport {

// ---- round protocol -------------------------------------------------------------------

/// Wire form of an outgoing protocol message (block or status) from `run_id`.
wire::PoseBlock to_wire_block(const PoseBlockMessage& m, const std::string& run_id, bool broadcast,
                              const std::vector<std::uint32_t>& recipients);
wire::RoundStatus to_wire_status(const RoundStatusMessage& m, const std::string& run_id,
                                 bool broadcast, const std::vector<std::uint32_t>& recipients);
PoseBlockMessage from_wire(const wire::PoseBlock& w);
RoundStatusMessage from_wire(const wire::RoundStatus& w);

/// Whether a routed message is meant for agent `me` (broadcast, or `me` among the recipients).
bool addressed_to(bool broadcast, const std::vector<std::uint32_t>& recipients, std::uint32_t me);

// ---- poses and measurements ------------------------------------------------------------

/// The content of a measurement hand-off, decoded.
struct HandoffContent {
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;       ///< Position of each in the original input.
  std::vector<std::pair<std::uint32_t, Pose>> poses;  ///< Initial poses (id, pose).
  /// A robust run's second candidate start (id, pose): the known inliers' initialization.
  std::vector<std::pair<std::uint32_t, Pose>> known_poses;
};
/// `known_poses` (a robust run's second start) travel in the hand-off's lifted fields at rank d,
/// which a purpose-0 hand-off does not use otherwise.
wire::MeasurementHandoff to_wire_handoff(
    const std::string& run_id, std::uint32_t sender, std::uint32_t recipient, int d,
    const std::vector<const Measurement*>& measurements,
    const std::vector<std::uint64_t>& measurement_index,
    const std::vector<std::pair<std::uint32_t, const Pose*>>& poses,
    const std::vector<std::pair<std::uint32_t, const Pose*>>& known_poses = {});
HandoffContent from_wire(const wire::MeasurementHandoff& w);

/// Poses (id, pose) of a final estimate.
std::vector<std::pair<std::uint32_t, Pose>> final_poses(const wire::FinalEstimate& w);

/// Serialized size in bytes of a wire message (what DDS puts on the wire, without headers).
template <class T>
std::size_t serialized_size(const T& sample) {
  return T::getCdrSerializedSize(sample) + 4;  // + encapsulation
}

}  // namespace tessera::transport
