// The gate an agent passes before announcing itself (transport/peer_gate.hpp) and the
// participant tags it reads (transport/participant_tags.hpp):
// - tags survive encoding; other software's user data reads as "no tags";
// - the decision: wait for the coordinator, move to UDP only when the coordinator does, and
//   in a secured run re-create exactly one side of a pair whose handshake stalled;
// - over DDS: agents started WITHOUT --udp-only for a coordinator that keeps replicas
//   re-create their participant UDP-only before announcing, the coordinator and the other
//   agents take the new participant for the old one (no "lost", no "two processes claim"),
//   and the run finishes; with a plain coordinator nothing is re-created;
// - secured runs count a participant's name and tags only once its handshake is authorized
//   (peer tracking and the gate), so an outsider advertising a member's name decides nothing.
// Domains 74-75.

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "dds_process_support.hpp"
#include "transport/participant_tags.hpp"
#include "transport/peer_gate.hpp"
#include "transport/peer_tracking.hpp"

namespace tessera::test::dds {
namespace {

using transport::GateStep;
using transport::ParticipantTags;
using transport::PeerIdentity;
using transport::PeerView;

TEST(ParticipantTags, RoundTripAndForeignBytesReadAsNoTags) {
  ParticipantTags t;
  EXPECT_TRUE(t.encode().empty()) << "a plain participant carries no user data";
  t.udp_only = true;
  t.replaces = {"1.f.78.fd.68.3b.14.90.0.0.0.0", "1.f.78.fd.68.3b.14.91.0.0.0.0"};
  const ParticipantTags back = ParticipantTags::decode(t.encode());
  EXPECT_TRUE(back.udp_only);
  EXPECT_EQ(back.replaces, t.replaces);

  ParticipantTags udp;
  udp.udp_only = true;
  const ParticipantTags only_udp = ParticipantTags::decode(udp.encode());
  EXPECT_TRUE(only_udp.udp_only);
  EXPECT_FALSE(only_udp.retiring);
  EXPECT_TRUE(only_udp.replaces.empty());
  ParticipantTags retiring;
  retiring.retiring = true;
  EXPECT_TRUE(ParticipantTags::decode(retiring.encode()).retiring);
  EXPECT_FALSE(ParticipantTags::decode(retiring.encode()).udp_only);

  auto bytes = [](const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); };
  for (const std::string& foreign :
       {std::string(), std::string("udp_only=1"), std::string("ros2;udp_only=1"),
        std::string("tessera-tagsX;udp_only=1"), std::string("\x01\x02\xff", 3)}) {
    const ParticipantTags f = ParticipantTags::decode(bytes(foreign));
    EXPECT_FALSE(f.udp_only) << foreign;
    EXPECT_TRUE(f.replaces.empty()) << foreign;
  }
  // Unknown keys are skipped, known ones still read; a list with an over-long or empty item,
  // or too many items, is ignored as a whole.
  for (const std::string& bad :
       {std::string(100, 'a'), std::string("a,,b"), std::string("a,b,c,d,e,f,g,h,i")}) {
    const ParticipantTags mixed =
        ParticipantTags::decode(bytes("tessera-tags;colour=blue;udp_only=1;junk;replaces=" + bad));
    EXPECT_TRUE(mixed.udp_only) << bad;
    EXPECT_TRUE(mixed.replaces.empty()) << bad;
  }
}

transport::SessionOptions agent_options(std::uint32_t id, bool shared_memory = true) {
  transport::SessionOptions o;
  o.run_id = "gate";
  o.agent_id = id;
  o.num_agents = 3;
  o.shared_memory = shared_memory;
  return o;
}

PeerView view(bool coordinator, std::uint32_t id, double known_for_s, bool authenticated,
              bool udp_only = false) {
  PeerView v;
  v.who = PeerIdentity{"gate", coordinator, coordinator ? 0u : id};
  v.known_for_s = known_for_s;
  v.authenticated = authenticated;
  v.tags.udp_only = udp_only;
  return v;
}

TEST(PeerGate, WaitsForTheCoordinatorThenPassesOrMovesToUdpOnly) {
  using transport::judge_peers;
  // Unsecured: only the coordinator matters.
  GateStep s = judge_peers(agent_options(1), false, {view(false, 0, 9, false)}, 4);
  EXPECT_EQ(s.kind, GateStep::kWait);
  EXPECT_NE(s.why.find("coordinator"), std::string::npos) << s.why;
  EXPECT_EQ(judge_peers(agent_options(1), false, {view(true, 0, 0.1, false)}, 4).kind,
            GateStep::kPass);
  // The coordinator talks UDP only: an agent with shared memory re-creates, one without passes.
  EXPECT_EQ(judge_peers(agent_options(1), false, {view(true, 0, 0.1, false, true)}, 4).kind,
            GateStep::kReopenUdpOnly);
  EXPECT_EQ(judge_peers(agent_options(1, false), false, {view(true, 0, 0.1, false, true)}, 4).kind,
            GateStep::kPass);
}

TEST(PeerGate, SecuredRunsWaitForEveryHandshakeAndOneSideOfAStalledPairReopens) {
  using transport::judge_peers;
  const double stall = 4;
  // Everyone authenticated: pass.
  EXPECT_EQ(
      judge_peers(agent_options(1), true,
                  {view(true, 0, 1, true), view(false, 0, 1, true), view(false, 2, 1, true)}, stall)
          .kind,
      GateStep::kPass);
  // A peer not discovered yet, or a handshake still young: wait, naming them.
  GateStep s = judge_peers(agent_options(1), true,
                           {view(true, 0, 1, true), view(false, 0, 1, false)}, stall);
  EXPECT_EQ(s.kind, GateStep::kWait);
  EXPECT_NE(s.why.find("agent 0 (not authenticated yet)"), std::string::npos) << s.why;
  EXPECT_NE(s.why.find("agent 2 (not discovered yet)"), std::string::npos) << s.why;
  // Stalled with a smaller id: agent 1 re-creates; agent 0 with agent 1 only waits.
  s = judge_peers(agent_options(1), true,
                  {view(true, 0, 9, true), view(false, 0, 5, false), view(false, 2, 9, true)},
                  stall);
  EXPECT_EQ(s.kind, GateStep::kReopenStalled);
  EXPECT_EQ(s.why, "agent 0");
  EXPECT_EQ(judge_peers(agent_options(0), true,
                        {view(true, 0, 9, true), view(false, 1, 5, false), view(false, 2, 9, true)},
                        stall)
                .kind,
            GateStep::kWait);
  // Stalled with the coordinator: always the agent's side.
  s = judge_peers(agent_options(0), true,
                  {view(true, 0, 5, false), view(false, 1, 9, true), view(false, 2, 9, true)},
                  stall);
  EXPECT_EQ(s.kind, GateStep::kReopenStalled);
  EXPECT_EQ(s.why, "the coordinator");
  // Not stalled yet at 3.9 s.
  EXPECT_EQ(
      judge_peers(agent_options(0), true,
                  {view(true, 0, 3.9, false), view(false, 1, 9, true), view(false, 2, 9, true)},
                  stall)
          .kind,
      GateStep::kWait);
}

// A restarted agent asking to rejoin cures every stalled handshake itself: its peers passed
// their gates and never re-create, so a stall with a running agent of larger id (agent 1 with
// agent 2 here) stayed until the coordinator gave up on the rejoin.
TEST(PeerGate, AJoiningAgentReopensForAStalledHandshakeWithAnyPeer) {
  using transport::judge_peers;
  const std::vector<PeerView> peers = {view(true, 0, 9, true), view(false, 0, 9, true),
                                       view(false, 2, 5, false)};
  EXPECT_EQ(judge_peers(agent_options(1), true, peers, 4).kind, GateStep::kWait);
  const GateStep s = judge_peers(agent_options(1), true, peers, 4, /*joining=*/true);
  EXPECT_EQ(s.kind, GateStep::kReopenStalled);
  EXPECT_EQ(s.why, "agent 2");
  // Still only once the handshake is older than the stall bound.
  EXPECT_EQ(
      judge_peers(agent_options(1), true,
                  {view(true, 0, 9, true), view(false, 0, 9, true), view(false, 2, 3.9, false)}, 4,
                  /*joining=*/true)
          .kind,
      GateStep::kWait);
}

// Impostors (unauthenticated participants advertising a member's name, as anyone can in
// plaintext SPDP data) next to the real, authenticated members: they neither hold the gate
// nor move the agent to UDP only.
TEST(PeerGate, SecuredRunsIgnoreUnauthenticatedClaimantsOfAnAuthenticatedRole) {
  using transport::judge_peers;
  const double stall = 4;
  const std::vector<PeerView> real = {view(true, 0, 1, true), view(false, 0, 1, true),
                                      view(false, 2, 1, true)};
  std::vector<PeerView> with_impostors = {view(true, 0, 60, false, /*udp_only=*/true),
                                          view(false, 0, 60, false), view(false, 2, 60, false)};
  with_impostors.insert(with_impostors.end(), real.begin(), real.end());
  EXPECT_EQ(judge_peers(agent_options(1), true, with_impostors, stall).kind, GateStep::kPass);
  // Only an unauthenticated coordinator that says "UDP only": no re-creation for its tag; its
  // handshake is judged like any other (stalled after 60 s).
  GateStep s = judge_peers(
      agent_options(1), true,
      {view(true, 0, 60, false, true), view(false, 0, 1, true), view(false, 2, 1, true)}, stall);
  EXPECT_EQ(s.kind, GateStep::kReopenStalled);
  EXPECT_EQ(s.why, "the coordinator");
  // Two unauthenticated claimants: stalled only when the most recent one is (a real peer
  // discovered 1 s ago may still finish its handshake).
  s = judge_peers(agent_options(1), true,
                  {view(true, 0, 1, true), view(false, 0, 60, false), view(false, 0, 1, false),
                   view(false, 2, 1, true)},
                  stall);
  EXPECT_EQ(s.kind, GateStep::kWait);
  EXPECT_NE(s.why.find("agent 0 (not authenticated yet)"), std::string::npos) << s.why;
}

transport::GuidPrefix prefix_of_byte(unsigned char b) {
  transport::GuidPrefix p;
  p.value[0] = b;
  return p;
}

// What a secured process counts from discovery: a participant's name, tags and leaving only
// once Fast DDS reported its handshake authorized (either order); a second *authenticated*
// claimant of a role is still a clash.
TEST(PeerTracking, SecuredRunsCountANameOnlyFromAnAuthenticatedParticipant) {
  transport::Mailroom room;
  transport::SessionOptions o = agent_options(1);
  o.security_dir = "/unused";  // only whether it is set matters to the tracker
  transport::PeerTracker t(room, o, PeerIdentity{"gate", false, 1});
  const PeerIdentity agent0{"gate", false, 0}, coord{"gate", true, 0}, me{"gate", false, 1};
  t.discovered(prefix_of_byte(1), agent0);
  EXPECT_TRUE(t.live_peers().empty()) << "counted before its handshake";
  t.authenticated(prefix_of_byte(1));
  ASSERT_EQ(t.live_peers().size(), 1u);
  // Impostors: agent 0's name with tags that would replace it and say "UDP only", this
  // process's own name, the coordinator's name; then they change their tags and leave.
  ParticipantTags evil;
  evil.udp_only = true;
  evil.replaces = {transport::prefix_text(prefix_of_byte(1))};
  t.discovered(prefix_of_byte(2), agent0, evil);
  t.discovered(prefix_of_byte(3), me);
  t.discovered(prefix_of_byte(4), coord, evil);
  ParticipantTags retiring;
  retiring.retiring = true;
  t.changed(prefix_of_byte(2), retiring);
  t.left(prefix_of_byte(2));
  t.dropped(prefix_of_byte(3));
  EXPECT_FALSE(room.stopped()) << room.stop_info()->reason;
  ASSERT_EQ(t.live_peers().size(), 1u);
  EXPECT_EQ(t.live_peers()[0].describe(), agent0.describe());
  EXPECT_TRUE(t.lost_agents().empty());
  // The gate still sees the remaining candidate, unauthenticated, behind the members.
  std::vector<PeerView> views = t.peer_views(true);
  ASSERT_EQ(views.size(), 2u);
  EXPECT_TRUE(views[0].authenticated);
  EXPECT_FALSE(views[1].authenticated);
  EXPECT_TRUE(views[1].who.coordinator);
  // A candidate that says it retires is no longer waited for (it speaks only for itself).
  t.changed(prefix_of_byte(4), retiring);
  EXPECT_EQ(t.peer_views(true).size(), 1u);
  EXPECT_FALSE(room.stopped());
  // The real coordinator, authorized before its discovery is reported: counted at discovery.
  t.authenticated(prefix_of_byte(5));
  t.discovered(prefix_of_byte(5), coord);
  EXPECT_EQ(t.live_peers().size(), 2u);
  EXPECT_FALSE(room.stopped());
  // A second participant that authenticates with agent 0's name: a real clash.
  t.discovered(prefix_of_byte(6), agent0);
  EXPECT_FALSE(room.stopped());
  t.authenticated(prefix_of_byte(6));
  ASSERT_TRUE(room.stopped());
  EXPECT_EQ(room.stop_info()->exit_code, 2);
  EXPECT_NE(room.stop_info()->reason.find("two processes claim to be agent 0"), std::string::npos)
      << room.stop_info()->reason;
}

TEST(PeerTracking, AnAuthenticatedMemberThatLeavesIsLostAndItsSuccessorReplacesIt) {
  transport::Mailroom room;
  transport::SessionOptions o = agent_options(1);
  o.security_dir = "/unused";
  transport::PeerTracker t(room, o, PeerIdentity{"gate", false, 1});
  const PeerIdentity agent0{"gate", false, 0};
  t.discovered(prefix_of_byte(1), agent0);
  t.authenticated(prefix_of_byte(1));
  // It re-creates its participant: retiring, then the successor (counted once authenticated).
  ParticipantTags retiring;
  retiring.retiring = true;
  t.changed(prefix_of_byte(1), retiring);
  t.left(prefix_of_byte(1));
  ParticipantTags next;
  next.replaces = {transport::prefix_text(prefix_of_byte(1))};
  t.discovered(prefix_of_byte(2), agent0, next);
  t.authenticated(prefix_of_byte(2));
  EXPECT_FALSE(room.stopped()) << room.stop_info()->reason;
  ASSERT_EQ(t.live_peers().size(), 1u);
  // The successor's lease expires: that is a loss.
  t.dropped(prefix_of_byte(2));
  ASSERT_TRUE(room.stopped());
  EXPECT_NE(room.stop_info()->reason.find("lost agent 0"), std::string::npos)
      << room.stop_info()->reason;
}

TEST(PeerTracking, UnsecuredRunsCountANameAtDiscovery) {
  transport::Mailroom room;
  transport::PeerTracker t(room, agent_options(1), PeerIdentity{"gate", false, 1});
  const PeerIdentity agent0{"gate", false, 0};
  t.discovered(prefix_of_byte(1), agent0);
  EXPECT_EQ(t.live_peers().size(), 1u);
  EXPECT_TRUE(t.peer_views(false)[0].authenticated);
  t.discovered(prefix_of_byte(2), agent0);
  ASSERT_TRUE(room.stopped());
  EXPECT_EQ(room.stop_info()->exit_code, 2);
}

TEST(PeerGate, OptionsAreChecked) {
  transport::PeerGateOptions o;
  EXPECT_NO_THROW(o.validate());
  o.stall_after_s = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = transport::PeerGateOptions{};
  o.max_reopens = -1;
  EXPECT_THROW(o.validate(), InputError);
  o = transport::PeerGateOptions{};
  o.retire_notice_s = -1;
  EXPECT_THROW(o.validate(), InputError);
  o = transport::PeerGateOptions{};
  o.timeout_s = 0;
  EXPECT_THROW(o.validate(), InputError);
}

// One run: coordinator with `coordinator_extra`, 3 agents started WITHOUT --udp-only.
struct GateRun {
  Process coord;
  std::vector<Process> agents;
};

GateRun run_three(int domain, const std::string& name,
                  const std::vector<std::string>& coordinator_extra) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 120 --robots 3 --seed 2");
  const std::string run = name + "-" + std::to_string(getpid());
  GateRun r;
  std::vector<std::string> c = {"--timeout", "20", "--run-timeout", "40"};
  c.insert(c.end(), coordinator_extra.begin(), coordinator_extra.end());
  r.coord = start(coordinator_args(3, run, domain, c), dir + "/coordinator.log");
  r.agents = start_agents(dir, graph, 3, run, domain, {"--timeout", "20"}, false);
  std::vector<Process*> all = all_of(r.coord, r.agents);
  EXPECT_TRUE(wait_all(all, 45)) << "a process hung";
  for (Process* p : all) EXPECT_EQ(p->exit_code, 0) << p->output();
  return r;
}

TEST(DdsPeerGate, AgentsOfAReplicaRunMoveToUdpOnlyByThemselvesAndTheRunFinishes) {
  GateRun r = run_three(74, "gate-udp", {"--replicas", "1", "--rejoin-timeout", "2"});
  for (Process& a : r.agents) {
    const std::string out = a.output();
    EXPECT_NE(out.find("the coordinator talks UDP only"), std::string::npos) << out;
    EXPECT_EQ(out.find("lost"), std::string::npos) << out;
  }
  const std::string co = r.coord.output();
  EXPECT_EQ(co.find("claim"), std::string::npos) << co;
  EXPECT_EQ(co.find("lost"), std::string::npos) << co;
}

TEST(DdsPeerGate, AgentsOfAPlainRunKeepTheirParticipant) {
  GateRun r = run_three(75, "gate-plain", {});
  for (Process& a : r.agents)
    EXPECT_EQ(a.output().find("re-creating"), std::string::npos) << a.output();
}

}  // namespace
}  // namespace tessera::test::dds
