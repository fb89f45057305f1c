// Runs whose domain's discovery multicast port (7400 + 250 domain) is held by another
// program's socket without SO_REUSEADDR (transport/fastdds/discovery_port.hpp): Fast DDS
// cannot open it, and before the fallback such a run discovered nobody (an online launch on a
// domain >= 102, inside Linux's ephemeral port range, once failed in CI with "0 of 3 readers
// matched after 30.0 s"). The port is held here on purpose, so the failure is not left to
// chance. Domains used here: 114-117 (each test its own).

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

#include "dds_process_support.hpp"
#include "transport/fastdds/discovery_port.hpp"

namespace tessera::test::dds {
namespace {

// A UDP socket bound to 0.0.0.0:`port` without SO_REUSEADDR, as any program's socket bound to
// port 0 may get it from the ephemeral range; closed on destruction.
class PlainUdpSocket {
 public:
  explicit PlainUdpSocket(std::uint16_t port) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_ANY);
    bound_ =
        fd_ >= 0 && ::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  }
  ~PlainUdpSocket() {
    if (fd_ >= 0) ::close(fd_);
  }
  PlainUdpSocket(const PlainUdpSocket&) = delete;
  PlainUdpSocket& operator=(const PlainUdpSocket&) = delete;
  bool bound() const { return bound_; }

 private:
  int fd_;
  bool bound_ = false;
};

TEST(DdsDiscoveryPort, ThePortOfADomainIsTheRtpsWellKnownOne) {
  EXPECT_EQ(transport::discovery_multicast_port(0), 7400);
  EXPECT_EQ(transport::discovery_multicast_port(136), 41400);
  EXPECT_EQ(transport::discovery_unicast_port(136, 0), 41410u);
  EXPECT_EQ(transport::discovery_unicast_port(136, 3), 41416u);
}

TEST(DdsDiscoveryPort, APortHeldWithoutReuseIsNotBindableAndIsAgainOnceReleased) {
  const std::uint16_t port = transport::discovery_multicast_port(114);
  ASSERT_TRUE(transport::discovery_port_bindable(port)) << "port " << port << " is in use";
  {
    PlainUdpSocket held(port);
    ASSERT_TRUE(held.bound());
    EXPECT_FALSE(transport::discovery_port_bindable(port));
  }
  EXPECT_TRUE(transport::discovery_port_bindable(port));
}

// The online roles talk UDP only: with the port held, they found each other only through the
// fallback's unicast announcements.
TEST(DdsDiscoveryPort, AnOnlineLaunchWhoseDiscoveryPortIsHeldEndsCertified) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const std::uint16_t port = transport::discovery_multicast_port(115);
  PlainUdpSocket held(port);
  ASSERT_TRUE(held.bound()) << "port " << port << " is in use";
  const std::string json = online_launch(dir, graph, 115, "--rate 20 --speedup 2");
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  // Every process says once which port was taken and what it does instead.
  const std::string agent_log = read_text_file(dir + "/logs/agent-0.log");
  EXPECT_NE(agent_log.find("UDP port " + std::to_string(port) +
                           " (discovery multicast port of DDS domain 115"),
            std::string::npos)
      << agent_log;
  EXPECT_NE(read_text_file(dir + "/logs/replay.log").find("by unicast to 127.0.0.1"),
            std::string::npos);
}

// A batch launch over UDP only (coordinator and agents, Session) and over Fast DDS's default
// pair (UDPv4 and shared memory): before the fallback, both ran into --timeout undiscovered.
TEST(DdsDiscoveryPort, BatchLaunchesOverUdpFinishWhileTheDiscoveryPortIsHeld) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 120 --robots 3");
  int domain = 116;
  for (const char* transport : {"udp", "default"}) {
    const std::uint16_t port = transport::discovery_multicast_port(domain);
    PlainUdpSocket held(port);
    ASSERT_TRUE(held.bound()) << "port " << port << " is in use";
    std::string out;
    EXPECT_EQ(run_command("timeout -s KILL 240 " + bin("tessera") + " launch " + graph +
                              " --agents 3 --domain " + std::to_string(domain) +
                              " --timeout 60 --transport " + transport + " --json " + dir + "/" +
                              transport + ".json 2>&1",
                          &out),
              0)
        << transport << ":\n"
        << out;
    EXPECT_EQ(json_text(read_text_file(dir + "/" + transport + ".json"), "certified"), "true")
        << transport;
    ++domain;
  }
}

}  // namespace
}  // namespace tessera::test::dds
