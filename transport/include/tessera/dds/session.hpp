#pragma once
// Public API of a distributed run over DDS (Fast DDS 2.9): the options every process of one run
// shares. Plain data; the processes check them when they start (InputError naming the option).

#include <string>
#include <vector>

namespace tessera::dds {

struct SessionOptions {
  /// Run id, 1..64 of [A-Za-z0-9_.-]: processes with the same id form one run.
  std::string run_id = "default";
  /// DDS domain 0..232; < 0: derived from the run id.
  int domain = -1;
  /// Participant lease, seconds (0.2..60): a dead peer is noticed after about this long.
  double lease_s = 2.0;
  /// IPv4 addresses of other hosts to contact by unicast (when multicast is not available).
  std::vector<std::string> peers;
  /// "default", or "lossy" for links that drop packets.
  std::string network = "default";
  /// "default" (shared memory + UDPv4), "shm" (this host only) or "udp".
  std::string transport = "default";
  /// DDS Security folder (CA, governance, identities); "" = off.
  std::string security_dir;
  /// Bound on each wait for peers during set-up and shutdown, seconds (> 0).
  double timeout_s = 30;

  /// The command-line options that carry these settings (as tessera-agent and
  /// tessera-coordinator take them); `with_timeout` false leaves --timeout out.
  std::vector<std::string> argv(bool with_timeout = true) const;
};

}  // namespace tessera::dds
