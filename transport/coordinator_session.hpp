#pragma once
// The coordinator's DDS session: the shared part (transport/session.hpp) plus what only the
// coordinator reads and sends: the agents' announcements, round statuses, progress digests,
// reports, final estimates and rejoin requests in, partition assignments out.

#include "tessera.h"
#include "transport/inbox.hpp"
#include "transport/session.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

class CoordinatorSession final : public Session {
 public:
  /// Creates the participant and the coordinator's endpoints (`options.coordinator` must be
  /// true); throws InputError for bad options, TransportError on failure.
  explicit CoordinatorSession(const SessionOptions& options);

  // ---- inboxes: messages of this run from the agents --------------------------------------
  Inbox<wire::AgentAnnouncement>& announcements();
  /// The round statuses it reads (topic_names.hpp, coordinator_reads_status).
  Inbox<wire::RoundStatus>& status_watch();
  /// The agents' progress digests (agent/progress_digest.hpp).
  Inbox<wire::AgentProgress>& progress();
  /// Agent 0's reports (core/runtime/agent_report.hpp; transport/report_mapping.hpp decodes them).
  Inbox<wire::AgentReport>& reports();
  Inbox<wire::FinalEstimate>& finals();
  Inbox<wire::Control>& rejoins();  ///< REJOIN requests of restarted agents.

  // ---- sending (retries while the history is full; throws TransportError after write_timeout_s)
  void publish(const wire::PartitionAssignment& m);
};

}  // namespace tessera::transport
