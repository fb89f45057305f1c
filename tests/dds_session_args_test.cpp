// The DDS session options shared by tessera-agent, tessera-coordinator and tessera launch
// (cli/session_args.*): parsing, checks that name the option, and forwarding to the
// processes of a launch. No participant is created here.

#include <gtest/gtest.h>

#include <algorithm>
#include <tessera/util/input_error.hpp>

#include "launch/launch_transport.hpp"
#include "session_args.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using namespace tessera::cli;
using namespace tessera::launch;

SessionArgs parse(const std::vector<std::string>& argv, SessionArgsFor who) {
  Arguments args(argv, session_option_names(who), {});
  return parse_session_args(args, who);
}

std::string error_of(const std::vector<std::string>& argv, SessionArgsFor who) {
  try {
    parse(argv, who);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DdsSessionArgs, DefaultsMatchTheSessionDefaults) {
  SessionArgs a = parse({}, SessionArgsFor::kProcess);
  const transport::SessionOptions defaults;
  EXPECT_EQ(a.session.run_id, "default");
  EXPECT_EQ(a.session.domain, -1);
  EXPECT_EQ(a.session.lease_s, defaults.lease_s);
  EXPECT_TRUE(a.session.initial_peers.empty());
  EXPECT_EQ(a.timeout_s, 30);
}

TEST(DdsSessionArgs, ForwardedOptionsParseBackToTheSameSession) {
  SessionArgs a = parse(
      {"--run-id", "r-1.x", "--domain", "0", "--lease", "2.5", "--peers", "10.0.0.1,,10.0.0.2"},
      SessionArgsFor::kLaunch);
  EXPECT_EQ(a.session.initial_peers, (std::vector<std::string>{"10.0.0.1", "10.0.0.2"}));
  SessionArgs b = parse(session_argv(a.session), SessionArgsFor::kProcess);
  EXPECT_EQ(b.session.run_id, "r-1.x");
  EXPECT_EQ(b.session.domain, 0);
  EXPECT_EQ(b.session.lease_s, 2.5);
  EXPECT_EQ(b.session.initial_peers, a.session.initial_peers);
  // Defaults are not spelled out: only the run id is always passed on.
  EXPECT_EQ(session_argv(transport::SessionOptions{}),
            (std::vector<std::string>{"--run-id", "default"}));
}

TEST(DdsSessionArgs, BadValuesNameTheOption) {
  const auto P = SessionArgsFor::kProcess;
  EXPECT_NE(error_of({"--domain", "233"}, P).find("--domain"), std::string::npos);
  EXPECT_NE(error_of({"--domain", "-1"}, P).find("--domain"), std::string::npos);
  EXPECT_NE(error_of({"--lease", "0.1"}, P).find("--lease"), std::string::npos);
  EXPECT_NE(error_of({"--lease", "x"}, P).find("--lease"), std::string::npos);
  EXPECT_NE(error_of({"--peers", "10.0.0"}, P).find("--peers"), std::string::npos);
  EXPECT_NE(error_of({"--run-id", "a b"}, P).find("--run-id"), std::string::npos);
  EXPECT_NE(error_of({"--timeout", "0"}, P).find("--timeout"), std::string::npos);
  const std::string net = error_of({"--network", "wifi"}, P);
  EXPECT_NE(net.find("--network"), std::string::npos) << net;
  EXPECT_NE(net.find("lossy"), std::string::npos) << net;  // lists the valid names
}

TEST(DdsSessionArgs, NetworkProfileIsForwardedOnlyWhenNotDefault) {
  SessionArgs a = parse({"--network", "lossy"}, SessionArgsFor::kLaunch);
  EXPECT_EQ(a.session.network, "lossy");
  EXPECT_EQ(parse(session_argv(a.session), SessionArgsFor::kProcess).session.network, "lossy");
  a.session.network = "default";
  const auto argv = session_argv(a.session);
  EXPECT_EQ(std::find(argv.begin(), argv.end(), "--network"), argv.end());
}

TEST(DdsSessionArgs, TransportIsForwardedOnlyWhenNotDefaultAndShmExcludesPeers) {
  const auto P = SessionArgsFor::kProcess;
  for (const std::string t : {"shm", "udp"}) {
    SessionArgs a = parse({"--transport", t}, SessionArgsFor::kLaunch);
    EXPECT_EQ(a.session.transport, t);
    EXPECT_EQ(parse(session_argv(a.session), P).session.transport, t);
  }
  const auto argv = session_argv(transport::SessionOptions{});
  EXPECT_EQ(std::find(argv.begin(), argv.end(), "--transport"), argv.end());
  const std::string bad = error_of({"--transport", "tcp"}, P);
  EXPECT_NE(bad.find("--transport"), std::string::npos) << bad;
  EXPECT_NE(bad.find("shm"), std::string::npos) << bad;  // lists the valid names
  const std::string peers = error_of({"--transport", "shm", "--peers", "10.0.0.1"}, P);
  EXPECT_NE(peers.find("--transport"), std::string::npos) << peers;
  EXPECT_NE(peers.find("--peers"), std::string::npos) << peers;
  EXPECT_EQ(error_of({"--transport", "udp", "--peers", "10.0.0.1"}, P), "");
}

TEST(DdsSessionArgs, TransportsFollowTheRoleAndTheChoice) {
  transport::SessionOptions o;
  EXPECT_TRUE(o.uses_shared_memory() && o.uses_udp());
  o.transport = "shm";
  EXPECT_TRUE(o.uses_shared_memory());
  EXPECT_FALSE(o.uses_udp());
  o.transport = "udp";
  EXPECT_FALSE(o.uses_shared_memory());
  EXPECT_TRUE(o.uses_udp());
  // A role that survives killed processes talks UDP only, whatever --transport says.
  o.transport = "shm";
  o.shared_memory = false;
  EXPECT_FALSE(o.uses_shared_memory());
  EXPECT_TRUE(o.uses_udp());
}

TEST(DdsSessionArgs, LaunchUsesSharedMemoryOnlyWhenEveryPeerIsOnThisHost) {
  const LaunchLossOptions stop;
  EXPECT_EQ(launch_transport(parse({}, SessionArgsFor::kLaunch).session, stop), "shm");
  for (const std::vector<std::string>& argv : {std::vector<std::string>{"--peers", "10.0.0.1"},
                                               std::vector<std::string>{"--network", "lossy"}}) {
    EXPECT_EQ(launch_transport(parse(argv, SessionArgsFor::kLaunch).session, stop), "default")
        << argv[0];
  }
  transport::SessionOptions secured;
  secured.security_dir = "/some/dir";  // not validated here: only the choice is
  EXPECT_EQ(launch_transport(secured, stop), "default");
  LaunchLossOptions carry_on;
  carry_on.action = AgentLossAction::kContinue;
  EXPECT_EQ(launch_transport(transport::SessionOptions{}, carry_on), "default");
}

TEST(DdsSessionArgs, LaunchGivesALargeTeamUdpAndALongerLeaseUnlessTold) {
  const LaunchLossOptions stop;
  const transport::SessionOptions here = parse({}, SessionArgsFor::kLaunch).session;
  EXPECT_EQ(launch_transport(here, stop, kMaxSharedMemoryAgents), "shm");
  EXPECT_EQ(launch_transport(here, stop, kMaxSharedMemoryAgents + 1), "udp");
  EXPECT_EQ(
      launch_transport(parse({"--peers", "10.0.0.1"}, SessionArgsFor::kLaunch).session, stop, 64),
      "default");
  EXPECT_EQ(launch_lease_s(1.0, false, kMaxSharedMemoryAgents), 1.0);
  EXPECT_EQ(launch_lease_s(1.0, false, 64), kLargeTeamLeaseS);
  EXPECT_EQ(launch_lease_s(2.5, true, 64), 2.5) << "an explicit --lease is kept";
}

TEST(DdsSessionArgs, LaunchKeepsItsOwnTimeout) {
  // `tessera launch --timeout` is the whole run's limit, not the processes' set-up bound.
  EXPECT_TRUE(session_option_names(SessionArgsFor::kProcess).count("timeout"));
  EXPECT_FALSE(session_option_names(SessionArgsFor::kLaunch).count("timeout"));
  EXPECT_NE(session_options_help(SessionArgsFor::kProcess).find("--timeout"), std::string::npos);
  EXPECT_EQ(session_options_help(SessionArgsFor::kLaunch).find("--timeout"), std::string::npos);
}

TEST(DdsSessionArgs, SecurityFolderIsCheckedAndForwarded) {
  const std::string missing =
      error_of({"--security", "/nonexistent/tessera-sec"}, SessionArgsFor::kProcess);
  EXPECT_NE(missing.find("--security"), std::string::npos) << missing;
  EXPECT_NE(missing.find("/nonexistent/tessera-sec"), std::string::npos) << missing;
  // A folder with the shared files passes parsing (the role's own files are checked later).
  const std::string dir = tessera::test::temp_dir();
  const std::string no_governance = error_of({"--security", dir}, SessionArgsFor::kLaunch);
  EXPECT_NE(no_governance.find("ca_cert.pem"), std::string::npos) << no_governance;
  tessera::test::write_file(dir, "ca_cert.pem", "x");
  tessera::test::write_file(dir, "governance.p7s", "x");
  SessionArgs a = parse({"--security", dir}, SessionArgsFor::kLaunch);
  EXPECT_EQ(parse(session_argv(a.session), SessionArgsFor::kProcess).session.security_dir, dir);
}

}  // namespace
