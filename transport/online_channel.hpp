#pragma once
// The agents' own topics in an online run (agent/online_agent.cpp): the round protocol's pose
// blocks and statuses, tagged with the epoch (the solve of the growing graph they belong to),
// and the per-epoch reports (OnlineReport: batches held, block poses). Its own participant, as
// the graph stream's: an online run has no coordinator hand-shake (the agents agree on the
// graph through the reports), so the Session's set-up topics have nothing to carry.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <tessera/distributed/newton_refine_options.hpp>
#include <tessera/online/absorb_gate.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

#include "cli/run_wide_options.hpp"

namespace tessera::transport {

inline constexpr const char* kOnlineBlockTopic = "tessera_online_block";
inline constexpr const char* kOnlineStatusTopic = "tessera_online_status";
inline constexpr const char* kOnlineReportTopic = "tessera_online_report";
inline constexpr const char* kOnlineEstimateTopic = "tessera_online_estimate";

/// The options every agent of an online run must share: each agent moves the blocks itself
/// (the re-partition), and the Newton steps' coarse correction adds message steps to every CG
/// iteration of every agent. (OnlineOptions::place_new_poses and align_merged_pieces shape
/// every agent's estimate too, but no flag sets them: every agent runs with their defaults.)
struct OnlineTeamOptions {
  RebalanceOptions rebalance;
  /// OnlineOptions::newton_coarse, newton_coarse_min_blocks and newton_coarse_aggregates
  /// (their defaults here too; 0 = auto).
  NewtonRefineOptions::Coarse step_coarse = NewtonRefineOptions::Coarse::kNone;
  int step_coarse_min_blocks = 3;
  int step_coarse_aggregates = 8;
  /// OnlineOptions' run-wide solver options (their online defaults here too).
  cli::RunWideOptions run_wide;
};

struct OnlineReportSample {
  std::uint32_t epoch = 0;
  std::uint32_t sender = 0;
  Watermarks held;
  bool converged = false;
  int rank = 0, dim = 0;
  std::vector<std::uint32_t> pose_ids;
  std::vector<double> data;  ///< r*(d+1) per pose, column-major.
  /// Agent 0's reports: the agents that take part in the next epoch (joiners admitted).
  std::vector<std::uint32_t> next_members;
  bool certify = false;  ///< Agent 0's reports: certify at this epoch.
  /// Take-over votes (epoch kTakeoverEpoch): the agents the sender counts as lost and the
  /// epoch it was in; `held` is then what entered its graph.
  std::vector<std::uint32_t> lost;
  std::uint32_t at_epoch = 0;
  /// The sender's team options, on received reports (a channel writes its own agent's,
  /// OnlineChannel's `team`, into every report it sends): all must be the lead's
  /// (agent/online_agent.cpp checks).
  OnlineTeamOptions team;
};

/// The epoch of a hello: an agent that is not a member yet asks to join.
inline constexpr std::uint32_t kHelloEpoch = 0xFFFFFFFFu;
/// The epoch of a take-over vote: a member was lost and the survivors agree on its block.
inline constexpr std::uint32_t kTakeoverEpoch = 0xFFFFFFFEu;

/// A protocol message as received, with its routing (ids are the epoch's protocol ids).
struct OnlineProtocolSample {
  std::uint32_t epoch = 0;
  std::uint32_t sender = 0;
  bool broadcast = true;
  std::vector<std::uint32_t> recipients;
  ProtocolMessage message;
};

/// Participant lease of an online agent, seconds (as a batch Session's default: 2 s leaves room
/// for a loaded host, where 1 s declared live peers lost).
constexpr double kDefaultOnlineLeaseS = 2.0;

class OnlineChannel {
 public:
  /// Joins `domain` with partition `run_id` (validated: InputError). `agents` sizes the
  /// history limits. `lease_s`: the participant lease, seconds (a member silent that long is
  /// lost). `team`: this agent's team options, carried by every report it sends.
  /// Throws std::runtime_error when DDS refuses.
  OnlineChannel(int domain, const std::string& run_id, std::uint32_t agent, std::uint32_t agents,
                double lease_s = kDefaultOnlineLeaseS, const OnlineTeamOptions& team = {});
  ~OnlineChannel();
  OnlineChannel(const OnlineChannel&) = delete;
  OnlineChannel& operator=(const OnlineChannel&) = delete;

  /// Sends one protocol message of `epoch`; returns its serialized size in bytes.
  std::size_t send(const OutgoingMessage& m, std::uint32_t epoch);
  /// Sends a report; returns its serialized size in bytes.
  std::size_t send_report(const OnlineReportSample& r);
  /// Publishes a robot's current estimate (this agent's robot unless `robot` says which: a
  /// lost agent's robot whose block this agent adopted): pose indices and [R | t] (d*(d+1)
  /// values per pose, column-major).
  void publish_estimate(std::uint32_t epoch, int d, const std::vector<std::uint64_t>& index,
                        const std::vector<double>& poses, std::uint32_t robot = kOwnRobot);
  static constexpr std::uint32_t kOwnRobot = 0xFFFFFFFFu;
  /// Blocks until something arrived since the last take (or `timeout_s` passed).
  bool wait(double timeout_s);
  std::vector<OnlineReportSample> take_reports();
  std::vector<OnlineProtocolSample> take_messages();
  /// Fewest peers matched by any of this agent's protocol writers and readers (itself
  /// included): a message is delivered reliably to a reader its writer has matched.
  int matched_peers() const;
  /// Waits until every matched reader acknowledged what was sent, at most `timeout_s`.
  void flush(double timeout_s);
  /// Agents (ids from their participant names) whose participant left or whose liveliness
  /// lease expired, and that were not discovered again since.
  std::vector<std::uint32_t> lost_agents() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera::transport
