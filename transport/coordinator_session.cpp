// CoordinatorSession (coordinator_session.hpp): the coordinator's inboxes and its
// assignment sends, forwarded to the parts that own them (session_parts.hpp).

#include "transport/coordinator_session.hpp"

#include "transport/session_parts.hpp"
#include "transport/topic_names.hpp"

namespace tessera::transport {

CoordinatorSession::CoordinatorSession(const SessionOptions& options) : Session(options, true) {}

Inbox<wire::AgentAnnouncement>& CoordinatorSession::announcements() {
  return parts().announce_in;
}

Inbox<wire::RoundStatus>& CoordinatorSession::status_watch() {
  return parts().status_in;
}

Inbox<wire::AgentProgress>& CoordinatorSession::progress() {
  return parts().progress_in;
}

Inbox<wire::AgentReport>& CoordinatorSession::reports() {
  return parts().report_in;
}

Inbox<wire::FinalEstimate>& CoordinatorSession::finals() {
  return parts().final_in;
}

Inbox<wire::Control>& CoordinatorSession::rejoins() {
  return parts().rejoin_in;
}

void CoordinatorSession::publish(const wire::PartitionAssignment& m) {
  parts().writer.write(kAssignmentTopic, m);
}

}  // namespace tessera::transport
