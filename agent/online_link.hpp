#pragma once
// The DDS side of an online agent (agent/online_agent.cpp): reads the graph stream into the
// view and the channel into the epochs' reports, the queued protocol messages and the
// take-over votes; sends; and every wait of the run, each bounded by --timeout and each
// ending in TakeoverNeeded when a member was lost (--on-agent-loss continue). The decisions
// made from what it read are the epoch step's (agent/online_epoch_step.hpp).

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "agent/online_agent_state.hpp"
#include "runtime/epoch_message_queue.hpp"
#include "transport/graph_stream_topic.hpp"
#include "transport/online_channel.hpp"

namespace tessera::agent {

class OnlineLink {
 public:
  /// Joins the run's stream and channel; reads into and counts for `state`.
  explicit OnlineLink(OnlineAgentState& state);

  /// Takes the stream batches that arrived into the view.
  void pump_stream();
  /// Takes the reports and protocol messages that arrived: admissions go to the membership,
  /// reports of this epoch and later are kept, as are protocol messages. Throws when a
  /// take-over vote counts this agent lost, and InputError when the lead's report carries
  /// other team options than this agent's.
  void pump_channel();
  /// Agents whose participant left or whose lease lapsed (OnlineChannel::lost_agents).
  std::vector<std::uint32_t> lost_agents() const { return channel_.lost_agents(); }
  /// Throws TakeoverNeeded when --on-agent-loss continue and a member was lost (or a
  /// survivor voted so).
  void check_losses();

  /// Sends this agent's report of an epoch (or its hello).
  void send_report(const transport::OnlineReportSample& report);
  /// The reports of `epoch` kept so far, by sender.
  std::map<std::uint32_t, transport::OnlineReportSample>& reports(std::uint32_t epoch) {
    return reports_[epoch];
  }
  /// Forgets the reports of `epoch` (read).
  void drop_reports(std::uint32_t epoch) { reports_.erase(epoch); }
  /// The take-over votes read since the last call.
  std::vector<transport::OnlineReportSample> take_votes();
  /// Drops what belongs to the epochs below `epoch` (abandoned at a take-over).
  void drop_before(std::uint32_t epoch);

  /// Waits until every member of the epoch is matched on the protocol topics.
  void wait_matched();
  /// Waits until every member's report of the epoch arrived.
  void wait_for_reports();
  /// Waits until the view holds the batches of `decision`. With `read_channel` it reads the
  /// channel too (see the definition for why a take-over's own wait does not).
  void wait_to_hold(const Watermarks& decision, bool read_channel);
  /// The idle wait of a converged epoch that let nothing in: blocks, sending nothing, until a
  /// robot absorbed at this epoch holds more than `decision`, a joiner waits for the lead to
  /// admit it, or the next epoch's report arrived.
  void wait_for_news(const Watermarks& decision);
  /// The round protocol of the epoch's solve, until `agent` (this agent's block `me`) is done.
  void run_rounds(CertifiedAgent& agent, std::uint32_t me);

  /// Publishes this agent's robots' estimate (--publish-every, --tum-dir).
  void publish_estimate();
  /// The channel itself, for the take-over's vote (agent/takeover_vote.hpp).
  transport::OnlineChannel& channel() { return channel_; }
  /// Waits until the peers acknowledged what was sent, at most `timeout_s`.
  void flush(double timeout_s) { channel_.flush(timeout_s); }

 private:
  void send(const std::vector<OutgoingMessage>& out);
  /// Files a report read from the channel (hellos, votes and epoch reports apart).
  void file_report(transport::OnlineReportSample&& r);
  [[noreturn]] void silent_peer(const std::string& what) const;

  OnlineAgentState& s_;
  transport::GraphStreamReader stream_;
  transport::OnlineChannel channel_;
  std::map<std::uint32_t, std::map<std::uint32_t, transport::OnlineReportSample>> reports_;
  std::vector<transport::OnlineReportSample> votes_;  // take-over votes not yet read
  std::set<std::uint32_t> refused_;  // hellos with other team options (not admitted)
  runtime::EpochMessageQueue<transport::OnlineProtocolSample> pending_;
};

}  // namespace tessera::agent
