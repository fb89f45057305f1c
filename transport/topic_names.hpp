#pragma once
// The DDS topic of every message type (one topic per type; Partition QoS = run id on top).
// All start with "tessera_": the permissions of scripts/security/make_identities.sh grant
// "tessera_*". Shared by the session and the tools that watch a run (tessera-dds-snoop).

namespace tessera::transport {

inline constexpr const char* kAnnounceTopic = "tessera_announce";
inline constexpr const char* kAssignmentTopic = "tessera_assignment";
inline constexpr const char* kHandoffTopic = "tessera_handoff";
inline constexpr const char* kBlockTopic = "tessera_pose_block";
inline constexpr const char* kStatusTopic = "tessera_round_status";
inline constexpr const char* kFinalTopic = "tessera_final";
inline constexpr const char* kControlTopic = "tessera_control";

}  // namespace tessera::transport
