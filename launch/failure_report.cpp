#include "launch/failure_report.hpp"

namespace tessera::launch {

namespace {

// The tail with this agent's own marker `tessera-agent[K]` made anonymous, so that the same
// message from two agents compares equal.
std::string anonymous_tail(const FailedProcess& p) {
  if (p.agent < 0) return p.tail;
  const std::string own = "tessera-agent[" + std::to_string(p.agent) + "]";
  const std::string anonymous = "tessera-agent[*]";
  std::string out = p.tail;
  for (std::size_t at = out.find(own); at != std::string::npos;
       at = out.find(own, at + anonymous.size()))
    out.replace(at, own.size(), anonymous);
  return out;
}

}  // namespace

std::string FailureGroup::label() const {
  if (members.size() == 1) return members.front()->name;
  std::string ids;
  for (std::size_t k = 0; k < members.size(); ++k) {
    if (k > 0) ids += k + 1 == members.size() ? " and " : ", ";
    ids += std::to_string(members[k]->agent);
  }
  return "agents " + ids;
}

std::vector<FailureGroup> group_failures(const std::vector<FailedProcess>& failed) {
  std::vector<FailureGroup> groups;
  std::vector<std::string> keys;
  for (const FailedProcess& p : failed) {
    // Only agents share a group: the coordinator's messages are its own.
    const std::string key =
        p.agent < 0 ? std::string() : std::to_string(p.code) + "\n" + anonymous_tail(p);
    std::size_t g = 0;
    while (g < groups.size() && (key.empty() || keys[g] != key)) ++g;
    if (g == groups.size()) {
      groups.emplace_back();
      keys.push_back(key);
    }
    groups[g].members.push_back(&p);
  }
  return groups;
}

int exit_code_after_failure(const std::vector<FailedProcess>& failed) {
  bool agent_failed = false, coordinator_input_error = false;
  for (const FailedProcess& p : failed) {
    if (p.agent < 0) {
      coordinator_input_error = p.code == 2;
      continue;
    }
    if (p.code != 2) return 1;
    agent_failed = true;
  }
  return agent_failed || coordinator_input_error ? 2 : 1;
}

}  // namespace tessera::launch
