// launch/free_domain.hpp on a folder and files that stand for /dev/shm, /proc/locks and
// /proc/net/udp: a domain with a locked shared-memory port or a bound discovery port is in use,
// and a launch without --domain moves on to the next domain that is not.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "launch/free_domain.hpp"
#include "test_support.hpp"
#include "transport/run_identity.hpp"

namespace tessera::launch {
namespace {

struct FakeHost {
  FakeHost() : dir(test::temp_dir()) {
    probe.shm_dir = dir;
    probe.locks = dir + "/locks";
    probe.udp = dir + "/udp";
    std::ofstream(probe.locks) << "";
    std::ofstream(probe.udp) << "  sl  local_address rem_address   st\n";
  }
  // A port file of `port` with its lock file, locked (as /proc/locks would list it) or not.
  void shm_port(long port, bool locked) {
    const std::string base = dir + "/fastrtps_port" + std::to_string(port);
    std::ofstream(base) << "";
    std::ofstream(base + "_el") << "";
    struct stat st {};
    stat((base + "_el").c_str(), &st);
    if (locked)
      std::ofstream(probe.locks, std::ios::app)
          << "1: FLOCK  ADVISORY  WRITE 4242 00:1b:" << st.st_ino << " 0 EOF\n";
  }
  void udp_bound(long port) {
    char hex[8];
    std::snprintf(hex, sizeof(hex), "%04lX", port);
    std::ofstream(probe.udp, std::ios::app)
        << " 1275: 00000000:" << hex << " 00000000:0000 07 00000000:00000000\n";
  }
  std::string dir;
  DomainProbe probe;
};

TEST(LaunchFreeDomain, ADomainWithALockedSharedMemoryPortIsInUseAndTheNextOneIsTaken) {
  FakeHost host;
  host.shm_port(7400 + 250 * 40 + 11, true);  // a participant's unicast port on domain 40
  host.shm_port(7400 + 250 * 41, false);      // a dead participant's port on domain 41
  EXPECT_TRUE(domain_in_use(40, host.probe));
  EXPECT_FALSE(domain_in_use(41, host.probe));
  EXPECT_EQ(free_domain_from(40, host.probe), 41);
  EXPECT_EQ(free_domain_from(39, host.probe), 39);
}

TEST(LaunchFreeDomain, ADomainWhoseDiscoveryPortIsBoundIsInUse) {
  FakeHost host;
  host.udp_bound(7400 + 250 * 7);
  host.udp_bound(7400 + 250 * 8 + 10);  // a unicast port of domain 8 does not count
  EXPECT_TRUE(domain_in_use(7, host.probe));
  EXPECT_FALSE(domain_in_use(8, host.probe));
  EXPECT_EQ(free_domain_from(7, host.probe), 8);
}

TEST(LaunchFreeDomain, TheSearchWrapsFromTheLastDomainToTheFirst) {
  FakeHost host;
  host.udp_bound(7400 + 250 * transport::kMaxDomain);
  EXPECT_EQ(free_domain_from(transport::kMaxDomain, host.probe), 1);
}

}  // namespace
}  // namespace tessera::launch
