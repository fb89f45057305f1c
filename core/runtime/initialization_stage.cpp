#include "runtime/initialization_stage.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/flat_measurement.hpp>
#include <tessera/graph/flat_pose.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/util/input_error.hpp>
#include <variant>

#include "distributed/measurement_block.hpp"

namespace tessera::agent {

namespace {

enum InitPhase : std::uint32_t {
  kChordalMeasurements = kInitPhaseBase,  // agent k -> agent 0: the values it recorded
  kChordalPoses,                          // agent 0 -> all: the chordal poses of every pose
  kUnitPoses = kInitPhaseBase + 10,       // agent k -> agent 0: unit poses at inter-robot ends
  kUnitCount,                             // all -> all: number of units (status: cost)
  kCrossing,                              // agent k -> agent 0: inter-robot measurements recorded
  kUnitFrames,                            // agent 0 -> all: every unit's frame
  kSetupTurnDone = kInitPhaseBase + 20    // agent a -> a + K: my local solve is done (turns)
};

std::uint32_t phase_of(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.phase; }, m);
}
std::uint32_t sender_of(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.sender; }, m);
}

// Receives until every agent of `senders` has sent its message of `phase`; keeps messages of
// the stage's other phases for later. A message of another stage cannot arrive (see the header),
// except the second stage of run_initialization_stages(), which runs on the same mailbox with
// its phases moved by `offset` so its messages are kept, not mistaken for the first's.
class StageMailbox {
 public:
  StageMailbox(ProtocolChannel& channel, double timeout_s, std::uint32_t self)
      : channel_(channel), timeout_s_(timeout_s), self_(self) {}

  void set_offset(std::uint32_t offset) { offset_ = offset; }
  double timeout_s() const { return timeout_s_; }
  void send(OutgoingMessage m) {
    std::visit([&](auto& x) { x.phase += offset_; }, m.message);
    channel_.send(m);
  }

  std::map<std::uint32_t, ProtocolMessage> gather(std::uint32_t stage_phase,
                                                  const std::vector<std::uint32_t>& senders) {
    return gather(stage_phase, senders, timeout_s_);
  }
  // With its own bound: a wait that spans other agents' turns of computation (setup_turns.hpp).
  std::map<std::uint32_t, ProtocolMessage> gather(std::uint32_t stage_phase,
                                                  const std::vector<std::uint32_t>& senders,
                                                  double timeout_s) {
    const std::uint32_t phase = stage_phase + offset_;
    for (;;) {
      auto& have = stash_[phase];
      std::string missing;
      for (auto s : senders)
        if (!have.count(s)) missing += " " + std::to_string(s);
      if (missing.empty()) break;
      std::optional<ProtocolMessage> msg = channel_.receive(timeout_s);
      if (!msg)
        throw std::runtime_error("agent " + std::to_string(self_) + ": initialisation step " +
                                 std::to_string(phase) + ": nothing received for " +
                                 std::to_string(timeout_s) + " s; waiting for agent(s)" + missing);
      const std::uint32_t p = phase_of(*msg);
      if (p < kInitPhaseBase)
        throw std::runtime_error("agent " + std::to_string(self_) + ": a message of phase " +
                                 std::to_string(p) + " from agent " +
                                 std::to_string(sender_of(*msg)) +
                                 " arrived during the initialisation");
      stash_[p][sender_of(*msg)] = std::move(*msg);
    }
    auto out = std::move(stash_[phase]);
    stash_.erase(phase);
    return out;
  }

 private:
  ProtocolChannel& channel_;
  double timeout_s_;
  std::uint32_t self_;

  std::uint32_t offset_ = 0;
  std::map<std::uint32_t, std::map<std::uint32_t, ProtocolMessage>> stash_;
};

PoseBlockMessage block(std::uint32_t self, std::uint32_t phase, std::uint32_t rank, int d) {
  PoseBlockMessage m;
  m.sender = self;
  m.phase = phase;
  m.rank = rank;
  m.dim = static_cast<std::uint32_t>(d);
  return m;
}

std::size_t width_of(const PoseBlockMessage& m) {
  return static_cast<std::size_t>(m.rank) * (m.dim + 1);
}

std::vector<std::uint32_t> others(std::uint32_t self, std::uint32_t n) {
  std::vector<std::uint32_t> o;
  for (std::uint32_t a = 0; a < n; ++a)
    if (a != self) o.push_back(a);
  return o;
}

// Sorts by file position and refuses duplicates (each measurement lives in one share).
std::vector<Measurement> in_file_order(std::vector<std::pair<std::uint64_t, Measurement>> all) {
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Measurement> out;
  out.reserve(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (k > 0 && all[k].first == all[k - 1].first)
      throw std::runtime_error("initialisation: measurement #" + std::to_string(all[k].first) +
                               " was sent by two agents");
    out.push_back(std::move(all[k].second));
  }
  return out;
}

std::vector<Pose> chordal_stage(const RobotShare& share, std::uint32_t self, std::uint32_t N,
                                const std::string& source, StageMailbox& mail, EarlyChordal* early,
                                bool* used_early) {
  const int d = share.d;
  const std::size_t width = flat_pose_size(d);
  std::vector<const Measurement*> mine;
  for (const auto& m : share.measurements) mine.push_back(&m);
  if (self != 0) {
    mail.send(OutgoingMessage{
        encode_measurement_block(self, kChordalMeasurements, d, mine, share.measurement_index),
        false,
        {0}});
    const auto got = mail.gather(kChordalPoses, {0});
    const auto& m = std::get<PoseBlockMessage>(got.at(0));
    if (m.rank != static_cast<std::uint32_t>(d) || m.data.size() != m.pose_ids.size() * width)
      throw std::runtime_error("initialisation: malformed chordal poses from agent 0");
    std::vector<Pose> out(share.end - share.begin);
    std::vector<bool> seen(out.size(), false);
    for (std::size_t k = 0; k < m.pose_ids.size(); ++k) {
      const std::uint32_t id = m.pose_ids[k];
      if (id < share.begin || id >= share.end) continue;
      out[id - share.begin] = read_flat_pose(m.data, k * width, d);
      seen[id - share.begin] = true;
    }
    if (std::find(seen.begin(), seen.end(), false) != seen.end())
      throw std::runtime_error("initialisation: agent 0's chordal poses miss some of ours");
    return out;
  }
  // Agent 0: the whole graph, measurements in file order, as `tessera solve` reads it.
  std::vector<std::pair<std::uint64_t, Measurement>> all;
  for (std::size_t k = 0; k < share.measurements.size(); ++k)
    all.emplace_back(share.measurement_index[k], share.measurements[k]);
  for (auto& [sender, msg] : mail.gather(kChordalMeasurements, others(self, N)))
    decode_measurement_block(std::get<PoseBlockMessage>(msg), d, share.num_poses, "initialisation",
                             all);
  PoseGraph graph;
  graph.d = d;
  graph.num_poses = share.num_poses;
  graph.source = source;
  graph.measurements = in_file_order(std::move(all));
  std::optional<std::vector<Pose>> solved;
  if (early) solved = early->take_if_same(graph);
  if (used_early) *used_early = solved.has_value();
  const std::vector<Pose> poses = solved ? std::move(*solved) : chordal_initialization(graph);
  if (N > 1) {
    PoseBlockMessage out = block(self, kChordalPoses, static_cast<std::uint32_t>(d), d);
    for (std::size_t id = 0; id < poses.size(); ++id) {
      out.pose_ids.push_back(static_cast<std::uint32_t>(id));
      append_flat_pose(out.data, poses[id], width);
    }
    mail.send(OutgoingMessage{std::move(out), true, {}});
  }
  return std::vector<Pose>(poses.begin() + share.begin, poses.begin() + share.end);
}

// Agent 0: every agent's unit poses at inter-robot ends and inter-robot measurements, aligned
// into one frame per unit (align_units), sent to every other agent.
std::vector<Pose> unit_frames_of_agent0(const RobotShare& share, const PoseBlockMessage& ends,
                                        std::uint32_t N, const std::vector<std::size_t>& offset,
                                        const std::vector<const Measurement*>& crossing_mine,
                                        const std::vector<std::uint64_t>& crossing_index,
                                        StageMailbox& mail, double wait_s) {
  const int d = share.d;
  const std::uint32_t self = 0;
  const std::uint32_t unit_rank = static_cast<std::uint32_t>(d + 1);
  const std::vector<Pose> frame = [&] {
    auto end_poses = mail.gather(kUnitPoses, others(self, N), wait_s);
    end_poses[self] = ends;
    std::map<std::size_t, UnitPose> endpoint;
    for (const auto& [a, msg] : end_poses) {
      const auto& m = std::get<PoseBlockMessage>(msg);
      const std::size_t w = width_of(m);
      if (m.rank != unit_rank || m.dim != static_cast<std::uint32_t>(d) ||
          m.data.size() != m.pose_ids.size() * w)
        throw std::runtime_error("initialisation: malformed unit poses from agent " +
                                 std::to_string(a));
      for (std::size_t k = 0; k < m.pose_ids.size(); ++k) {
        const double u = m.data[k * w + flat_pose_size(d)];
        if (!(u >= 0 && u < static_cast<double>(offset[a + 1] - offset[a])))
          throw std::runtime_error("initialisation: agent " + std::to_string(a) +
                                   " named a unit it does not have");
        endpoint[m.pose_ids[k]] = {offset[a] + static_cast<std::size_t>(u),
                                   read_flat_pose(m.data, k * w, d)};
      }
    }
    std::vector<std::pair<std::uint64_t, Measurement>> all;
    for (std::size_t k = 0; k < crossing_mine.size(); ++k)
      all.emplace_back(crossing_index[k], *crossing_mine[k]);
    for (auto& [a, msg] : mail.gather(kCrossing, others(self, N), wait_s))
      decode_measurement_block(std::get<PoseBlockMessage>(msg), d, share.num_poses,
                               "initialisation", all);
    const std::vector<Measurement> crossing = in_file_order(std::move(all));
    return align_units(d, offset[N], crossing, endpoint);
  }();
  if (N > 1) {
    PoseBlockMessage out = block(self, kUnitFrames, static_cast<std::uint32_t>(d), d);
    const std::size_t width = flat_pose_size(d);
    for (std::size_t u = 0; u < frame.size(); ++u) {
      out.pose_ids.push_back(static_cast<std::uint32_t>(u));
      append_flat_pose(out.data, frame[u], width);
    }
    mail.send(OutgoingMessage{std::move(out), true, {}});
  }
  return frame;
}

// Another agent: the units' frames from agent 0.
std::vector<Pose> received_unit_frames(StageMailbox& mail, int d, std::size_t num_units,
                                       double wait_s) {
  const auto got = mail.gather(kUnitFrames, {0}, wait_s);
  const auto& m = std::get<PoseBlockMessage>(got.at(0));
  const std::size_t width = flat_pose_size(d);
  if (m.rank != static_cast<std::uint32_t>(d) || m.data.size() != m.pose_ids.size() * width ||
      m.pose_ids.size() != num_units)
    throw std::runtime_error("initialisation: malformed unit frames from agent 0");
  std::vector<Pose> frame(num_units);
  for (std::size_t k = 0; k < num_units; ++k) {
    if (m.pose_ids[k] != k)
      throw std::runtime_error("initialisation: malformed unit frames from agent 0");
    frame[k] = read_flat_pose(m.data, k * width, d);
  }
  return frame;
}

std::vector<Pose> distributed_stage(
    const RobotShare& share, std::uint32_t self, std::uint32_t N,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::string& source, StageMailbox& mail, const SetupTurnOptions& turns,
    std::uint64_t* total_units) {
  const int d = share.d;
  auto mine = [&](std::size_t id) { return id >= share.begin && id < share.end; };
  // 1. Our own units (what this robot computes alone), in our turn (setup_turns.hpp). Each
  //    wait may span the solves before ours in the chain, each bounded by the timeout; what
  //    follows waits for every agent, so for the longest chain.
  const SetupTurn turn = setup_turn(self, N, turns.max_at_once);
  const double wait_s = mail.timeout_s() * turn.chain_length;
  if (turn.waits_for)
    mail.gather(kSetupTurnDone, {*turn.waits_for}, mail.timeout_s() * turn.position);
  const RobotUnits units = robot_units(d, share.begin, share.end, share.measurements, source);
  if (turns.after_local_solve) turns.after_local_solve();
  if (turn.passes_to) {
    RoundStatusMessage done;
    done.sender = self;
    done.phase = kSetupTurnDone;
    mail.send(OutgoingMessage{done, false, {*turn.passes_to}});
  }
  std::vector<std::pair<std::size_t, std::size_t>> slot(share.end - share.begin);
  for (std::size_t u = 0; u < units.members.size(); ++u)
    for (std::size_t k = 0; k < units.members[u].size(); ++k)
      slot[units.members[u][k] - share.begin] = {u, k};
  // 2. Our poses at the ends of inter-robot measurements (from the whole structure: some
  //    were recorded by other robots), and the inter-robot measurements we recorded.
  std::set<std::size_t> boundary;
  for (const auto& [i, j] : structure)
    if (mine(i) != mine(j)) boundary.insert(mine(i) ? i : j);
  const std::uint32_t unit_rank = static_cast<std::uint32_t>(d + 1);  // [R, t, unit] fits
  PoseBlockMessage ends = block(self, kUnitPoses, unit_rank, d);
  const std::size_t unit_width = width_of(ends);
  for (std::size_t id : boundary) {
    const auto [u, k] = slot[id - share.begin];
    ends.pose_ids.push_back(static_cast<std::uint32_t>(id));
    append_flat_pose(ends.data, units.poses[u][k], unit_width);
    ends.data[ends.data.size() - unit_width + flat_pose_size(d)] = static_cast<double>(u);
  }
  std::vector<const Measurement*> crossing_mine;
  std::vector<std::uint64_t> crossing_index;
  for (std::size_t k = 0; k < share.measurements.size(); ++k)
    if (!mine(share.measurements[k].i) || !mine(share.measurements[k].j)) {
      crossing_mine.push_back(&share.measurements[k]);
      crossing_index.push_back(share.measurement_index[k]);
    }
  RoundStatusMessage count;
  count.sender = self;
  count.phase = kUnitCount;
  count.cost = static_cast<double>(units.members.size());
  // Agent 0 aligns the units and sends every agent their frames (one pose a unit): the
  // alignment needs every inter-robot measurement and the unit poses at both its ends, which
  // in every agent grew with the team and the graph (302,994 inter-robot measurements on a 1M
  // grid over 64 robots, several hundred MB an agent). Agent 0 computes what each agent
  // computed before, from the same data, so the frames are the same.
  if (N > 1) {
    if (self != 0) {
      mail.send(OutgoingMessage{ends, false, {0}});
      mail.send(OutgoingMessage{
          encode_measurement_block(self, kCrossing, d, crossing_mine, crossing_index), false, {0}});
    }
    mail.send(OutgoingMessage{count, true, {}});
  }
  // 3. Everyone's: unit numbering in agent order (ranges tile 0..n-1 in agent order, so this
  //    is the order of the units' smallest poses, as in the in-process engine).
  auto counts = mail.gather(kUnitCount, others(self, N), wait_s);
  counts[self] = count;
  std::vector<std::size_t> offset(N + 1, 0);
  for (std::uint32_t a = 0; a < N; ++a) {
    const double c = std::get<RoundStatusMessage>(counts.at(a)).cost;
    if (!(c >= 1 && c <= static_cast<double>(share.num_poses)))
      throw std::runtime_error("initialisation: agent " + std::to_string(a) +
                               " reported an impossible number of units");
    offset[a + 1] = offset[a] + static_cast<std::size_t>(c);
  }
  const std::vector<Pose> frame = self == 0
                                      ? unit_frames_of_agent0(share, ends, N, offset, crossing_mine,
                                                              crossing_index, mail, wait_s)
                                      : received_unit_frames(mail, d, offset[N], wait_s);
  std::vector<Pose> out(share.end - share.begin);
  for (std::size_t u = 0; u < units.members.size(); ++u)
    for (std::size_t k = 0; k < units.members[u].size(); ++k)
      out[units.members[u][k] - share.begin] =
          place_in_frame(frame[offset[self] + u], units.poses[u][k]);
  *total_units = offset[N];
  return out;
}

}  // namespace

std::string default_initialization() {
  return init_name(DistributedOptions{}.initialization);
}

namespace {

InitializationResult run_stage(
    const RobotShare& share, std::uint32_t self, std::uint32_t num_agents,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::string& method, const std::string& source, StageMailbox& mail, EarlyChordal* early,
    const SetupTurnOptions& turns) {
  const auto t0 = std::chrono::steady_clock::now();
  InitializationResult res;
  res.method = method.empty() ? default_initialization() : method;
  const DistributedInit init = parse_init(res.method);
  if (init == DistributedInit::kFile) {
    if (share.initial.size() != share.end - share.begin)
      throw InputError(source, 0,
                       "initialisation 'file' needs a VERTEX line for every pose of robot " +
                           std::to_string(self) + " (poses " + std::to_string(share.begin) + ".." +
                           std::to_string(share.end - 1) + "); use --init chordal or distributed");
    res.poses = share.initial;
  } else if (init == DistributedInit::kChordal) {
    res.poses = chordal_stage(share, self, num_agents, source, mail, early, &res.early);
  } else {
    res.poses =
        distributed_stage(share, self, num_agents, structure, source, mail, turns, &res.units);
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace

InitializationResult run_initialization_stage(
    const RobotShare& share, std::uint32_t self, std::uint32_t num_agents,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::string& method, const std::string& source, ProtocolChannel& channel,
    double timeout_s, EarlyChordal* early, const SetupTurnOptions& turns) {
  turns.validate();
  StageMailbox mail(channel, timeout_s, self);
  return run_stage(share, self, num_agents, structure, method, source, mail, early, turns);
}

std::pair<InitializationResult, InitializationResult> run_initialization_stages(
    const RobotShare& share, const RobotShare& second_share, std::uint32_t self,
    std::uint32_t num_agents, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& second_structure,
    const std::string& method, const std::string& second_method, const std::string& source,
    ProtocolChannel& channel, double timeout_s, EarlyChordal* early,
    const SetupTurnOptions& turns) {
  turns.validate();
  StageMailbox mail(channel, timeout_s, self);
  InitializationResult first =
      run_stage(share, self, num_agents, structure, method, source, mail, early, turns);
  mail.set_offset(kSecondStagePhaseOffset);
  InitializationResult second = run_stage(second_share, self, num_agents, second_structure,
                                          second_method, source, mail, nullptr, turns);
  return {std::move(first), std::move(second)};
}

}  // namespace tessera::agent
