#pragma once
// How a run is named on the wire: run id rules, the DDS domain derived from it, and the
// participant names that let a process tell which peer (agent k or the coordinator) it
// has discovered or lost.

#include <cstdint>
#include <optional>
#include <string>

namespace tessera::transport {

/// Sender id the coordinator uses in messages (agents are 0..N-1).
constexpr std::uint32_t kCoordinatorId = 0xFFFFFFFFu;

/// Highest usable domain id (UDP ports are 7400 + 250 * domain and must stay below 65536).
constexpr int kMaxDomain = 232;

/// Throws InputError unless `run_id` is 1..64 characters of [A-Za-z0-9_.-].
void validate_run_id(const std::string& run_id);

/// A domain id in 1..kMaxDomain derived from the run id (stable FNV-1a hash), so that
/// concurrent runs with different ids are usually on different domains. Partition QoS and
/// the run id field keep runs apart even when two ids share a domain.
int domain_for_run(const std::string& run_id);

/// Who a participant is.
struct PeerIdentity {
  std::string run_id;
  bool coordinator = false;
  std::uint32_t agent_id = 0;  ///< Meaningful when !coordinator.

  /// "agent 3" or "the coordinator".
  std::string describe() const;
};

/// "tessera:<run>:agent:<k>" or "tessera:<run>:coordinator".
std::string participant_name(const PeerIdentity& who);
/// The inverse of participant_name; nullopt for names not made by it (other software).
std::optional<PeerIdentity> parse_participant_name(const std::string& name);

/// "tessera-online:<run>:<k>": agent k's participant of an online run (OnlineChannel). Not
/// parse_participant_name's form: an online agent is no Session peer of any run.
std::string online_participant_name(const std::string& run_id, std::uint32_t agent);
/// The agent id of an online_participant_name of run `run_id`; nullopt for any other name.
std::optional<std::uint32_t> parse_online_participant_name(const std::string& name,
                                                           const std::string& run_id);

/// This machine's host name (for announcements and messages).
std::string host_name();

}  // namespace tessera::transport
