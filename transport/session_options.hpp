#pragma once
// What a process needs to join a Tessera run over DDS: run id, domain, role, lease, unicast
// peers. Plain data with no Fast DDS types, so the command-line front ends (tessera launch,
// cli/session_args.*) can use it without linking Fast DDS.

#include <cstdint>
#include <string>
#include <vector>

namespace tessera::transport {

struct SessionOptions {
  std::string run_id = "default";  ///< 1..64 of [A-Za-z0-9_.-]; Partition QoS and message field.
  int domain = -1;                 ///< DDS domain 0..kMaxDomain; < 0: domain_for_run(run_id).
  bool coordinator = false;        ///< Role: the coordinator, or agent `agent_id`.
  std::uint32_t agent_id = 0;      ///< 0..num_agents-1 (agents only).
  std::uint32_t num_agents = 1;    ///< N >= 1.
  /// Participant lease and writer liveliness lease in seconds (0.2..60). A SIGKILLed peer is
  /// noticed after about this long (participant announcements go out every lease/5). 2 s: on a
  /// loaded host a live process can go unscheduled for over a second, and 1 s then counted it
  /// lost (docs/dds-runtime.md, "QoS").
  double lease_s = 2.0;
  /// IPv4 addresses of hosts to contact by unicast for discovery (when multicast is blocked).
  std::vector<std::string> initial_peers;
  /// Transport profile (network_profile.hpp): "default", or "lossy" for links that drop
  /// frames (small datagrams, big socket buffers).
  std::string network = "default";
  /// DDS Security folder (security.hpp; scripts/security/make_identities.sh): empty = off.
  /// On: authentication, access control and encryption with this process's identity
  /// (DIR/coordinator or DIR/agent_<k>), the CA and the signed governance in DIR.
  std::string security_dir;
  /// How long a write may wait for room in the bounded history before failing (seconds).
  double write_timeout_s = 30.0;
  /// Print discovery events (peer found / lost) to stderr.
  bool verbose = false;
  /// Whether the run has a coordinator (agents wait for it in the readiness barrier). Off
  /// only for agent-to-agent tools such as tessera-dds-ping.
  bool expect_coordinator = true;
  /// When true, losing an *agent* peer does not stop the session: it is recorded
  /// (lost_agents()) so the coordinator can wait for the agent to rejoin. Losing the
  /// coordinator always stops. Can be changed later with set_agent_loss_tolerated().
  bool tolerate_agent_loss = false;
  /// Use the shared-memory transport between processes of one host (faster). Off for runs
  /// that survive killed processes (see transport/qos.hpp participant_qos): UDP only.
  /// Set by the role (agent/coordinator options), not by --transport.
  bool shared_memory = true;
  /// --transport: which Fast DDS transports the participant opens. "default": shared memory
  /// (to processes of this host) and UDPv4; "shm": shared memory only, for runs whose every
  /// process is on this host (`tessera launch`): no UDP sockets, receive threads or interface
  /// scans at start-up; "udp": UDPv4 only. A role that must survive killed processes
  /// (`shared_memory` false) talks UDP whatever this says. "shm" excludes --peers.
  std::string transport = "default";

  /// Whether the participant opens the shared-memory transport (`shared_memory` and not
  /// --transport udp).
  bool uses_shared_memory() const { return shared_memory && transport != "udp"; }
  /// Whether the participant opens UDPv4 (always unless it uses shared memory only).
  bool uses_udp() const { return transport != "shm" || !uses_shared_memory(); }
  /// For log lines: "" with both transports, else " (UDP only)" / " (shared memory only)".
  const char* transports_note() const {
    return !uses_shared_memory() ? " (UDP only)" : !uses_udp() ? " (shared memory only)" : "";
  }

  /// Throws InputError naming the bad field (as its command-line option).
  void validate() const;
};

/// The names --transport accepts, in the order --help lists them ("default", "shm", "udp").
std::vector<std::string> transport_names();

}  // namespace tessera::transport
