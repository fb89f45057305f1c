// Unit tests of the DDS runtime's pure parts: message mapping (core types <-> wire types),
// inboxes and stop requests, run identity, and the agents' hand-off bookkeeping. No
// participant is created here.

#include <gtest/gtest.h>

#include <cmath>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/util/input_error.hpp>
#include <thread>
#include <variant>

#include "runtime/local_share.hpp"
#include "transport/epoch_routing.hpp"
#include "transport/inbox.hpp"
#include "transport/message_mapping.hpp"
#include "transport/report_mapping.hpp"
#include "transport/riding_blocks.hpp"
#include "transport/run_identity.hpp"
#include "transport/status_relay.hpp"
#include "transport/transport_error.hpp"

namespace {

using namespace tessera;
using namespace tessera::transport;

Pose pose2(double x, double y, double th) {
  Pose p = Pose::identity(2);
  p.R << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
  p.t << x, y;
  return p;
}

TEST(DdsMapping, PoseBlockRoundTripsExactly) {
  PoseBlockMessage m;
  m.round = 7;
  m.sender = 3;
  m.phase = 4;
  m.kind = BlockKind::kV;
  m.rank = 4;
  m.dim = 3;
  m.pose_ids = {5, 9};
  for (int k = 0; k < 2 * 4 * 4; ++k) m.data.push_back(0.1 * k - 1.0 / 3.0);
  wire::PoseBlock w = to_wire_block(m, "run", false, {1, 2});
  EXPECT_EQ(w.run_id(), "run");
  EXPECT_TRUE(addressed_to(w.broadcast(), w.recipients(), 2));
  EXPECT_FALSE(addressed_to(w.broadcast(), w.recipients(), 0));
  PoseBlockMessage back = from_wire(w);
  EXPECT_EQ(back.round, 7u);
  EXPECT_EQ(back.sender, 3u);
  EXPECT_EQ(back.phase, 4u);
  EXPECT_EQ(back.kind, BlockKind::kV);
  EXPECT_EQ(back.pose_ids, m.pose_ids);
  EXPECT_EQ(back.data, m.data);  // bit for bit
}

TEST(DdsMapping, MalformedPoseBlockIsRejected) {
  PoseBlockMessage m;
  m.rank = 3;
  m.dim = 2;
  m.pose_ids = {1};
  m.data = {1, 2, 3};  // needs 9
  EXPECT_THROW(from_wire(to_wire_block(m, "r", true, {})), TransportError);
  wire::PoseBlock w = to_wire_block(PoseBlockMessage{}, "r", true, {});
  w.kind(7);
  EXPECT_THROW(from_wire(w), TransportError);
}

TEST(DdsMapping, RoundStatusRoundTrips) {
  RoundStatusMessage m;
  m.round = 2;
  m.sender = 1;
  m.phase = 3;
  m.cost = 12.5;
  m.grad_norm_sq = 1e-9;
  m.block_grad_norm = 0.25;
  m.restart_vote = true;
  m.done_vote = false;
  m.near_bound = 17;
  m.coarse = {0.5, -1e-300, 3.0};
  RoundStatusMessage back = from_wire(to_wire_status(m, "r", true, {}));
  EXPECT_EQ(back.near_bound, 17u);
  EXPECT_EQ(back.coarse, m.coarse);
  EXPECT_EQ(back.round, 2u);
  EXPECT_EQ(back.phase, 3u);
  EXPECT_EQ(back.cost, 12.5);
  EXPECT_EQ(back.grad_norm_sq, 1e-9);
  EXPECT_EQ(back.block_grad_norm, 0.25);
  EXPECT_TRUE(back.restart_vote);
  EXPECT_FALSE(back.done_vote);
}

// The relay's bundles (transport/status_relay.hpp): every status of a step, exactly, and only
// once the relay's own is in; steps of an epoch abandoned by a rollback are dropped.
// Blocks riding in a status sample (transport/riding_blocks.hpp) come out as they went in,
// with the status's sender, in order; fields that do not describe whole blocks are refused.
TEST(DdsRidingBlocks, BlocksComeOutOfTheStatusExactlyAndInOrder) {
  auto block = [](std::uint32_t round, std::uint32_t phase, BlockKind kind,
                  std::vector<std::uint32_t> ids, double base) {
    PoseBlockMessage b;
    b.round = round;
    b.sender = 9;  // ignored: a riding block is the status sender's
    b.phase = phase;
    b.kind = kind;
    b.rank = 3;
    b.dim = 2;
    b.pose_ids = std::move(ids);
    for (std::size_t k = 0; k < b.pose_ids.size() * 9; ++k)
      b.data.push_back(base + 0.1 * static_cast<double>(k) + 1e-17 * static_cast<double>(k));
    return b;
  };
  const std::vector<PoseBlockMessage> in{block(12, 3, BlockKind::kY, {4, 7}, -1.5),
                                         block(12, 4, BlockKind::kV, {}, 0.0),
                                         block(13, 0, BlockKind::kP, {1}, 2.25)};
  wire::RoundStatus w;
  w.sender(2);
  w.round(12);
  w.phase(1);
  for (const auto& b : in) attach_block(w, b);
  EXPECT_EQ(w.block_header().size(), 18u);
  const std::vector<PoseBlockMessage> out = detach_blocks(w);
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {
    EXPECT_EQ(out[k].sender, 2u);
    EXPECT_EQ(out[k].round, in[k].round);
    EXPECT_EQ(out[k].phase, in[k].phase);
    EXPECT_EQ(out[k].kind, in[k].kind);
    EXPECT_EQ(out[k].rank, 3u);
    EXPECT_EQ(out[k].dim, 2u);
    EXPECT_EQ(out[k].pose_ids, in[k].pose_ids);
    EXPECT_EQ(out[k].data, in[k].data);  // bit for bit
  }
  // Detached means gone: the relay keeps the status without them.
  EXPECT_TRUE(w.block_header().empty() && w.block_pose_ids().empty() && w.block_data().empty());
  EXPECT_TRUE(detach_blocks(w).empty());

  wire::RoundStatus short_data;
  attach_block(short_data, in[0]);
  short_data.block_data().pop_back();
  EXPECT_THROW(detach_blocks(short_data), TransportError);
  wire::RoundStatus extra_id;
  attach_block(extra_id, in[2]);
  extra_id.block_pose_ids().push_back(5);
  EXPECT_THROW(detach_blocks(extra_id), TransportError);
  wire::RoundStatus cut_header;
  attach_block(cut_header, in[1]);
  cut_header.block_header().pop_back();
  EXPECT_THROW(detach_blocks(cut_header), TransportError);
  wire::RoundStatus bad_kind;
  attach_block(bad_kind, in[1]);
  bad_kind.block_header()[2] = 3;
  EXPECT_THROW(detach_blocks(bad_kind), TransportError);
}

TEST(DdsStatusRelay, BundlesCarryEveryStatusOfAStepExactly) {
  auto status = [](std::uint32_t sender, std::uint32_t epoch, double cost) {
    RoundStatusMessage m;
    m.round = 4;
    m.sender = sender;
    m.phase = 1;
    m.cost = cost;
    m.grad_norm_sq = cost / 3.0;
    m.block_grad_norm = 1.0 / (sender + 7.0);
    m.done_vote = sender == 2;
    if (sender == 1) m.coarse = {cost, -cost, 7.0};  // coarse terms: a variable-length record
    wire::RoundStatus w = to_wire_status(m, "r", true, {});
    w.epoch(epoch);
    return w;
  };
  ASSERT_TRUE(relayed_phase(1));
  ASSERT_TRUE(relayed_phase(5));
  ASSERT_FALSE(relayed_phase(101));
  ASSERT_FALSE(relayed_phase(200));
  StatusRelay relay(3);
  EXPECT_FALSE(relay.add(status(2, 0, 0.1), 0));
  EXPECT_FALSE(relay.add(status(1, 0, 0.2), 0));
  EXPECT_FALSE(relay.add(status(1, 1, 0.3), 0));              // the next epoch: another step
  EXPECT_TRUE(relay.take_bundles("r", kRelayAgent).empty());  // the relay's own is missing
  EXPECT_TRUE(relay.add(status(kRelayAgent, 0, 1e-300), 0));
  const std::vector<wire::RoundStatus> bundles = relay.take_bundles("r", kRelayAgent);
  ASSERT_EQ(bundles.size(), 1u);
  EXPECT_EQ(bundles[0].sender(), kRelayAgent);
  EXPECT_EQ(bundles[0].round(), 4u);
  EXPECT_EQ(bundles[0].epoch(), 0u);
  const std::vector<wire::RoundStatus> back = StatusRelay::unpack(bundles[0]);
  ASSERT_EQ(back.size(), 3u);
  const double costs[] = {1e-300, 0.2, 0.1};
  for (std::uint32_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back[k].sender(), k);  // in sender order
    EXPECT_EQ(back[k].run_id(), "r");
    EXPECT_EQ(back[k].round(), 4u);
    EXPECT_EQ(back[k].phase(), 1u);
    EXPECT_EQ(back[k].cost(), costs[k]);
    EXPECT_EQ(back[k].grad_norm_sq(), costs[k] / 3.0);
    EXPECT_EQ(back[k].block_grad_norm(), 1.0 / (k + 7.0));
    EXPECT_EQ(back[k].done_vote(), k == 2);
    EXPECT_FALSE(back[k].restart_vote());
    const std::vector<double> coarse =
        k == 1 ? std::vector<double>{0.2, -0.2, 7.0} : std::vector<double>{};
    EXPECT_EQ(back[k].coarse(), coarse);
  }
  EXPECT_TRUE(relay.take_bundles("r", kRelayAgent).empty());
  // A rollback to epoch 2: what epoch 1 collected is void, statuses of it are ignored.
  EXPECT_FALSE(relay.add(status(2, 1, 0.4), 2));
  EXPECT_FALSE(relay.add(status(kRelayAgent, 1, 0.4), 2));
  EXPECT_FALSE(relay.add(status(2, 2, 0.5), 2));
  EXPECT_FALSE(relay.add(status(1, 2, 0.5), 2));
  EXPECT_TRUE(relay.add(status(kRelayAgent, 2, 0.5), 2));
  ASSERT_EQ(relay.take_bundles("r", kRelayAgent).size(), 1u);

  wire::RoundStatus bad = bundles[0];
  bad.bundle().pop_back();
  EXPECT_THROW(StatusRelay::unpack(bad), TransportError);
  bad = bundles[0];
  bad.bundle()[0] = -1.0;
  EXPECT_THROW(StatusRelay::unpack(bad), TransportError);
  bad = bundles[0];
  bad.bundle()[6] = 1e9;  // a coarse count beyond the bundle
  EXPECT_THROW(StatusRelay::unpack(bad), TransportError);
}

TEST(DdsMapping, HandoffCarriesMeasurementsAndPosesExactly) {
  Measurement e;
  e.i = 4;
  e.j = 1;
  e.R = pose2(0, 0, 0.3).R;
  e.t = Eigen::Vector2d(1.5, -2.0);
  e.kappa = 10;
  e.tau = 20;
  Pose p = pose2(1, 2, -0.7);
  wire::MeasurementHandoff w = to_wire_handoff("r", 0, 1, 2, {&e}, {42}, {{4u, &p}});
  HandoffContent c = from_wire(w);
  ASSERT_EQ(c.measurements.size(), 1u);
  EXPECT_EQ(c.measurement_index, std::vector<std::uint64_t>{42});
  EXPECT_EQ(c.measurements[0].i, 4u);
  EXPECT_EQ(c.measurements[0].j, 1u);
  EXPECT_EQ(c.measurements[0].R, e.R);
  EXPECT_EQ(c.measurements[0].t, e.t);
  EXPECT_EQ(c.measurements[0].kappa, 10);
  EXPECT_EQ(c.measurements[0].tau, 20);
  ASSERT_EQ(c.poses.size(), 1u);
  EXPECT_EQ(c.poses[0].first, 4u);
  EXPECT_EQ(c.poses[0].second.R, p.R);
  EXPECT_EQ(c.poses[0].second.t, p.t);
  EXPECT_TRUE(c.known_poses.empty());
  w.meas_t().pop_back();
  EXPECT_THROW(from_wire(w), TransportError);
}

// A robust run's second start (the known inliers' initialization) rides in the lifted fields
// of a plain hand-off and comes back exactly; a replica's lifted data is not mistaken for it.
TEST(DdsMapping, HandoffCarriesTheKnownInliersStartExactly) {
  Pose p = pose2(1, 2, -0.7), q = pose2(-3, 0.5, 2.1);
  wire::MeasurementHandoff w = to_wire_handoff("r", 0, 1, 2, {}, {}, {{4u, &p}}, {{4u, &q}});
  HandoffContent c = from_wire(w);
  ASSERT_EQ(c.known_poses.size(), 1u);
  EXPECT_EQ(c.known_poses[0].first, 4u);
  EXPECT_EQ(c.known_poses[0].second.R, q.R);
  EXPECT_EQ(c.known_poses[0].second.t, q.t);
  EXPECT_EQ(c.poses[0].second.t, p.t);
  w.purpose(1);
  EXPECT_TRUE(from_wire(w).known_poses.empty());
  w.purpose(0);
  w.lifted_data().pop_back();
  EXPECT_THROW(from_wire(w), TransportError);
}

TEST(DdsRunIdentity, RunIdsDomainsAndNames) {
  EXPECT_NO_THROW(validate_run_id("run-1_a.b"));
  EXPECT_THROW(validate_run_id(""), InputError);
  EXPECT_THROW(validate_run_id("a b"), InputError);
  EXPECT_THROW(validate_run_id(std::string(65, 'x')), InputError);
  const int d = domain_for_run("abc");
  EXPECT_EQ(d, domain_for_run("abc"));
  EXPECT_GE(d, 1);
  EXPECT_LE(d, kMaxDomain);
  auto who = parse_participant_name(participant_name(PeerIdentity{"r-1", false, 12}));
  ASSERT_TRUE(who.has_value());
  EXPECT_EQ(who->run_id, "r-1");
  EXPECT_FALSE(who->coordinator);
  EXPECT_EQ(who->agent_id, 12u);
  who = parse_participant_name(participant_name(PeerIdentity{"r", true, 0}));
  ASSERT_TRUE(who.has_value());
  EXPECT_TRUE(who->coordinator);
  EXPECT_FALSE(parse_participant_name("ros2_node").has_value());
  EXPECT_FALSE(parse_participant_name("tessera:r:agent:x").has_value());
}

TEST(DdsInbox, WaitsWakeOnMessagesStopsAndTimeouts) {
  Mailroom room;
  Inbox<int> inbox(room);
  int got = 0;
  auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(inbox.take(Seconds(0.05), &got), WaitStatus::kTimeout);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(45));
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    inbox.push(1);
    inbox.push(2);
  });
  EXPECT_EQ(inbox.take([](int x) { return x == 2; }, Seconds(5), &got), WaitStatus::kReady);
  EXPECT_EQ(got, 2);
  producer.join();
  EXPECT_EQ(inbox.size(), 1u);
  EXPECT_EQ(inbox.wait_for([](const std::deque<int>& q) { return q.size() == 1; }, Seconds(1)),
            WaitStatus::kReady);
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    room.request_stop(3, "because");
  });
  EXPECT_EQ(inbox.take([](int x) { return x == 99; }, Seconds(5), &got), WaitStatus::kStopped);
  stopper.join();
  EXPECT_EQ(room.stop_info()->exit_code, 3);
  room.request_stop(4, "later");  // first reason wins
  EXPECT_EQ(room.stop_info()->reason, "because");
}

TEST(DdsInbox, DeferredStopTakesEffectUnlessAnotherComesFirst) {
  Mailroom room;
  room.request_stop_after(1, "peer left", Seconds(0.05));
  EXPECT_FALSE(room.stopped());
  EXPECT_EQ(room.wait_for([] { return false; }, Seconds(5)), WaitStatus::kStopped);
  EXPECT_EQ(room.stop_info()->reason, "peer left");
  Mailroom other;
  other.request_stop_after(1, "peer left", Seconds(1));
  other.request_stop(1, "the real cause", true);
  EXPECT_EQ(other.stop_info()->reason, "the real cause");
}

// A 9-pose chain split among 3 robots, then owned by a different partition.
TEST(DdsHandoff, EveryMeasurementReachesBothOwnersAndPosesTheirOwner) {
  PoseGraph g;
  g.d = 2;
  g.num_poses = 9;
  g.source = "test";
  for (int k = 0; k < 9; ++k) g.initial.push_back(pose2(k, 0, 0));
  auto add = [&](int i, int j) {
    Measurement m;
    m.i = i;
    m.j = j;
    m.R = Eigen::Matrix2d::Identity();
    m.t = Eigen::Vector2d(j - i, 0);
    g.measurements.push_back(m);
  };
  for (int k = 0; k + 1 < 9; ++k) add(k, k + 1);
  add(8, 0);
  add(2, 6);
  const std::vector<std::uint32_t> owner = {1, 1, 1, 0, 0, 2, 2, 2, 0};
  std::vector<agent::RobotShare> shares;
  for (std::uint32_t r = 0; r < 3; ++r) shares.push_back(agent::robot_share(g, r, 3));
  EXPECT_EQ(shares[1].begin, 3u);
  EXPECT_EQ(shares[1].end, 6u);
  std::size_t held = 0;
  for (const auto& s : shares) held += s.measurements.size();
  EXPECT_EQ(held, g.measurements.size());  // each measurement held by exactly one robot

  for (std::uint32_t a = 0; a < 3; ++a) {
    std::vector<agent::ReceivedHandoff> received;
    for (std::uint32_t b = 0; b < 3; ++b) {
      if (b == a) continue;
      agent::HandoffPlan plan = agent::plan_handoff(shares[b], owner, a);
      HandoffContent c = from_wire(
          to_wire_handoff("r", b, a, 2, plan.measurements, plan.measurement_index, plan.poses));
      received.push_back({b, c.measurements, c.measurement_index, c.poses, c.known_poses});
    }
    agent::AgentLocalData local = agent::assemble_local(shares[a], owner, a, 3, received, {});
    std::vector<std::uint64_t> expected;
    for (std::size_t k = 0; k < g.measurements.size(); ++k)
      if (owner[g.measurements[k].i] == a || owner[g.measurements[k].j] == a) expected.push_back(k);
    EXPECT_EQ(local.measurement_index, expected) << "agent " << a;
    ASSERT_EQ(local.initial.size(), local.owned.size());
    for (std::size_t k = 0; k < local.owned.size(); ++k)
      EXPECT_EQ(local.initial[k].t(0), static_cast<double>(local.owned[k]));
  }
}

TEST(DdsHandoff, InconsistentHandoffsAreReported) {
  PoseGraph g;
  g.d = 2;
  g.num_poses = 4;
  for (int k = 0; k < 4; ++k) g.initial.push_back(pose2(k, 0, 0));
  agent::RobotShare s = agent::robot_share(g, 0, 2);
  const std::vector<std::uint32_t> owner = {0, 0, 1, 0};
  // Pose 3 belongs to agent 0 but robot 1 never handed it over.
  EXPECT_THROW(agent::assemble_local(s, owner, 0, 2, {}, {}), std::runtime_error);
  EXPECT_THROW(agent::robot_share(g, 0, 5), InputError);
}

// The relay waiting in round 3's update step for the blocks of agents 1 and 4: agent 1's block
// rides in its status sample, so its block and its next status arrive together. A count of 2
// wakes the waiter there; the awaited set wakes it only with agent 4's block.
TEST(DdsEpochRouting, AwaitedSendersWakeTheWaiterOnlyWhenTheStepIsComplete) {
  auto block = [](std::uint32_t round, std::uint32_t sender) {
    PoseBlockMessage b;
    b.round = round, b.sender = sender, b.phase = 3;
    return ProtocolMessage(b);
  };
  auto status = [](std::uint32_t round, std::uint32_t sender) {
    RoundStatusMessage m;
    m.round = round, m.sender = sender, m.phase = 1;
    return ProtocolMessage(m);
  };
  Mailroom room;
  Inbox<ProtocolMessage> inbox(room), counted_inbox(room);
  EpochRouter router(room, inbox, 0), counted(room, counted_inbox, 0);
  router.set_awaited(AwaitedMessages{3, 3, {1, 4}});
  counted.set_wake_threshold(2);
  auto both = [&](ProtocolMessage m) {
    const bool a = router.deliver(0, 1, false, {0}, ProtocolMessage(m));
    const bool c = counted.deliver(0, 1, false, {0}, std::move(m));
    return std::make_pair(a, c);
  };
  auto ready = [&] { return room.with_lock([&] { return router.ready_locked(); }); };
  EXPECT_EQ(both(block(3, 1)), std::make_pair(false, false));
  EXPECT_EQ(both(status(4, 1)), std::make_pair(false, true));  // the count wakes too early
  EXPECT_FALSE(ready());
  EXPECT_EQ(both(block(2, 4)).first, false);  // agent 4, but an older round
  EXPECT_EQ(both(status(4, 2)).first, false);
  EXPECT_FALSE(ready());
  EXPECT_EQ(both(block(3, 4)).first, true);  // the step is complete
  EXPECT_TRUE(ready());

  // Set while the messages are already queued: ready at once; nullopt: any message again.
  router.set_awaited(AwaitedMessages{4, 1, {1, 2}});
  EXPECT_TRUE(ready());
  router.set_awaited(AwaitedMessages{4, 1, {3}});
  EXPECT_FALSE(ready());
  router.set_awaited(std::nullopt);
  EXPECT_TRUE(ready());
  EXPECT_TRUE(router.deliver(0, 3, false, {0}, status(4, 3)));
}

}  // namespace

namespace {

using namespace tessera;
using namespace tessera::transport;

// Agent 0's report through its wire form and back (report_mapping.hpp), with the envelope.
agent::AgentReport report_round_trip(const agent::AgentReport& r) {
  const wire::AgentReport w = to_wire_report(r, "run", 4, 2);
  EXPECT_EQ(w.run_id(), "run");
  EXPECT_EQ(w.sender(), 4u);
  EXPECT_EQ(w.epoch(), 2u);
  agent::AgentReport back = from_wire(w);
  EXPECT_EQ(back.index(), r.index());
  return back;
}

TEST(DdsReportMapping, EveryReportComesBackFieldForField) {
  const auto setup = std::get<agent::SetupTimesReport>(
      report_round_trip(agent::SetupTimesReport{0.0625, 1.0 / 3.0, true}));
  EXPECT_EQ(setup.initialization_s, 0.0625);
  EXPECT_EQ(setup.handoff_s, 1.0 / 3.0);
  EXPECT_TRUE(setup.initialization_early);

  const auto stage = std::get<agent::StageProgressReport>(report_round_trip(
      agent::StageProgressReport{agent::ProgressStage::kRefinement, (3ull << 32) | 412, 1.2e-3}));
  EXPECT_EQ(stage.stage, agent::ProgressStage::kRefinement);
  EXPECT_EQ(stage.iteration, (3ull << 32) | 412);
  EXPECT_EQ(stage.value, 1.2e-3);

  agent::CertificateReport c;
  c.certified = true;
  c.min_eigenvalue = -1.0625e-7;
  c.rounds = 3;
  c.final_rank = 7;
  c.bound.method = CertificateMethod::kLobpcg;
  c.bound.relaxation_cost = 1025.25;
  c.bound.trace_lambda = 1025.125;
  c.bound.gradient_norm = 3e-9;
  c.bound.shift = 2.5e-5;
  c.bound.lower_bound = 1024.5;
  const auto cert = std::get<agent::CertificateReport>(report_round_trip(c));
  EXPECT_TRUE(cert.certified);
  EXPECT_EQ(cert.min_eigenvalue, c.min_eigenvalue);
  EXPECT_EQ(cert.rounds, 3u);
  EXPECT_EQ(cert.final_rank, 7u);
  EXPECT_EQ(cert.bound.method, CertificateMethod::kLobpcg);
  EXPECT_EQ(cert.bound.relaxation_cost, 1025.25);
  EXPECT_EQ(cert.bound.trace_lambda, 1025.125);
  EXPECT_EQ(cert.bound.gradient_norm, 3e-9);
  EXPECT_EQ(cert.bound.shift, 2.5e-5);
  EXPECT_EQ(cert.bound.lower_bound, 1024.5);
  // An unproved bound stays unproved (NaN parts), and its method with it.
  agent::CertificateReport unproved;
  const auto none = std::get<agent::CertificateReport>(report_round_trip(unproved));
  EXPECT_FALSE(none.certified);
  EXPECT_EQ(none.bound.method, CertificateMethod::kNone);
  EXPECT_FALSE(none.bound.proved());
  EXPECT_TRUE(std::isnan(none.bound.shift));

  const auto traffic = std::get<agent::CertificateTrafficReport>(
      report_round_trip(agent::CertificateTrafficReport{(1ull << 40) + 3, 142578, 2}));
  EXPECT_EQ(traffic.certificate_bytes, (1ull << 40) + 3);
  EXPECT_EQ(traffic.escape_bytes, 142578u);
  EXPECT_EQ(traffic.escape_rounds, 2u);

  agent::RobustRunReport r;
  r.outer_iterations = 29;
  r.rejected = {1099, 1100, 1224};
  r.readmitted = 44;
  r.threshold_squared = 42.309352037278586;
  r.weights_converged = true;
  r.probes = 2;
  r.probes_kept = 1;
  r.refine_message_steps = 37;
  r.exchange_steps = 61;
  r.final_refine_steps = 3;
  r.solve_stages = 40;
  r.final_solve_stages = 2;
  const auto robust = std::get<agent::RobustRunReport>(report_round_trip(r));
  EXPECT_EQ(robust.outer_iterations, 29);
  EXPECT_EQ(robust.rejected, r.rejected);
  EXPECT_EQ(robust.readmitted, 44u);
  EXPECT_EQ(robust.threshold_squared, r.threshold_squared);
  EXPECT_TRUE(robust.weights_converged);
  EXPECT_EQ(robust.probes, 2);
  EXPECT_EQ(robust.probes_kept, 1);
  EXPECT_EQ(robust.refine_message_steps, 37);
  EXPECT_EQ(robust.exchange_steps, 61);
  EXPECT_EQ(robust.final_refine_steps, 3);
  EXPECT_EQ(robust.solve_stages, 40);
  EXPECT_EQ(robust.final_solve_stages, 2);

  const auto times = std::get<agent::PhaseTimesReport>(
      report_round_trip(agent::PhaseTimesReport{0.25, 0.125, 12, 348, 6}));
  EXPECT_EQ(times.solve_s, 0.25);
  EXPECT_EQ(times.rounding_s, 0.125);
  EXPECT_EQ(times.rounding_cg_iterations, 12u);
  EXPECT_EQ(times.rounding_interface_poses, 348u);
  EXPECT_EQ(times.rounding_message_steps, 6u);

  const auto fin = std::get<agent::FinalReport>(
      report_round_trip(agent::FinalReport{1025.3980556262577, 3.0791907055258897e-09, 5}));
  EXPECT_EQ(fin.cost, 1025.3980556262577);
  EXPECT_EQ(fin.grad_norm, 3.0791907055258897e-09);
  EXPECT_EQ(fin.restarts, 5u);
}

// A report the decoder cannot read (a stage or certificate method it does not know) is refused,
// named, instead of being read as some other value.
TEST(DdsReportMapping, UnknownStagesAndCertificateMethodsAreRefused) {
  wire::AgentReport w = to_wire_report(agent::StageProgressReport{}, "run", 0, 0);
  w.body().stage_progress().stage(9);
  EXPECT_THROW(from_wire(w), TransportError);
  wire::AgentReport c = to_wire_report(agent::CertificateReport{}, "run", 0, 0);
  c.body().certificate().method(3);
  EXPECT_THROW(from_wire(c), TransportError);
}

// The in-process estimate (message_bytes) counts a status's content; the DDS sample adds a
// fixed share of its own (run id, routing, epoch, relay fields, sequence lengths, padding), so
// more content grows both by the same bytes. Arrays start non-empty: CDR aligns a non-empty
// sequence of doubles, so the first element can bring padding.
TEST(DdsMapping, AStatusSampleGrowsByTheInProcessEstimatesGrowth) {
  RoundStatusMessage small;
  small.near_bound = 3;
  small.coarse = {1.0};
  small.measurement_ids = {4};
  small.weights = {0.5};
  RoundStatusMessage large = small;
  large.coarse.push_back(2.0);
  large.measurement_ids.insert(large.measurement_ids.end(), {8, 9});
  large.weights.insert(large.weights.end(), {1.0, 0.0});
  const auto sample_bytes = [](const RoundStatusMessage& m) {
    return serialized_size(to_wire_status(m, "run", true, {}));
  };
  EXPECT_EQ(message_bytes(large) - message_bytes(small), 5u * 8);
  EXPECT_EQ(sample_bytes(large) - sample_bytes(small), message_bytes(large) - message_bytes(small));
  EXPECT_GT(sample_bytes(small), message_bytes(small));
}

}  // namespace
