#pragma once
// The DDS domain of a `tessera launch` given no --domain: its run id's (transport::domain_for_run),
// or, when a live participant is already on that domain, the next domain that has none.
//
// Why: runs of different run ids on one domain disturb each other although Partition keeps their
// samples apart (docs/dds-runtime.md, "Tests and limits"): every participant hears the other
// run's discovery traffic, and over shared memory (launch's default transport) a Fast DDS 2.9.1
// listener can get stuck on a message of a participant that is deleted before it is read
// (transport/fastdds/shm_receive_watch.hpp). Two launches at once share a derived domain with
// probability 1/232; with this they never do, unless all 232 are in use.
//
// A domain D is in use when a Fast DDS shared-memory port of D (fastrtps_port<P>, P in
// 7400 + 250 D .. 7400 + 250 (D + 1) - 1) has its lock file (_el or _sl) locked by a live process
// (/proc/locks), or when UDP port 7400 + 250 D (D's discovery multicast port, bound by every UDP
// participant of D) is bound (/proc/net/udp). Read only: nothing is locked or opened for writing.
// No Fast DDS types.

#include <string>

namespace tessera::launch {

struct DomainProbe {
  std::string shm_dir = "/dev/shm";
  std::string locks = "/proc/locks";
  std::string udp = "/proc/net/udp";
};

/// Whether a live participant is on `domain` (see above).
bool domain_in_use(int domain, const DomainProbe& probe = {});

/// `first` if it is free, else the next free domain in 1..kMaxDomain (wrapping), else `first`.
int free_domain_from(int first, const DomainProbe& probe = {});

}  // namespace tessera::launch
