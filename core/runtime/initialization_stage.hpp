#pragma once
// The agents' initialisation, before the hand-off: every robot turns its share into initial
// poses for its own pose range, talking to the other agents only through a ProtocolChannel
// (the same seam as the round loop, so tests can drive it in process).
//
//   file         the share's VERTEX poses; no messages.
//   chordal      the centralized chordal initialization: every agent sends the measurement
//                values it recorded to agent 0, which solves it on the whole graph exactly as
//                `tessera solve` does (measurements in file order) and broadcasts the poses.
//                Centralized by definition (it is the reference); agent 0 sees every value.
//   distributed  no central solve
//   (core/include/tessera/distributed/distributed_initialization.hpp): each
//                robot runs chordal on its own measurements (robot_units); every robot then
//                broadcasts its unit count, its unit poses at the ends of inter-robot
//                measurements and the inter-robot measurements it recorded; each agent aligns
//                the units with the same breadth-first spanning tree (align_units) and keeps
//                its own poses. Same arithmetic as the in-process engine, so bit-identical
//                poses when the agents' shares are the generator's robot ranges. The local
//                solves take turns, a bounded number at once (runtime/setup_turns.hpp).
//
// Messages use phases kInitPhaseBase.. (>= 300), which the round protocol (0..5) and the
// rounding (100..) never use. Every message of the stage is consumed by
// its recipient before that recipient leaves the stage (nothing leaks into the round loop),
// and every agent sends its hand-off only after the stage, so no round message reaches an
// agent still in it.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/early_chordal.hpp"
#include "runtime/local_share.hpp"
#include "runtime/round_loop.hpp"
#include "runtime/setup_turns.hpp"

namespace tessera::agent {

constexpr std::uint32_t kInitPhaseBase = 300;
/// Phases of run_initialization_stages()' second stage: its own phases plus this (< 400).
constexpr std::uint32_t kSecondStagePhaseOffset = 50;

/// The initialisation name an empty RunOptions::initialization stands for: the in-process
/// engine's default (DistributedOptions), so `tessera launch` and `tessera solve` agree.
std::string default_initialization();

struct InitializationResult {
  std::string method;       ///< What ran ("chordal", "distributed", "file").
  std::vector<Pose> poses;  ///< Initial poses of [share.begin, share.end).
  std::uint64_t units = 0;  ///< distributed: units (robot components) of the whole graph.
  /// chordal, agent 0: the poses came from the EarlyChordal solve (the gathered graph was it).
  bool early = false;
  double seconds = 0.0;
};

/// Runs the initialisation `method` ("" = default_initialization()) for agent `self` of
/// `num_agents`, holding `share`. `structure`: endpoints of every measurement of the whole graph
/// (from the assignment; used to find this robot's poses at the ends of inter-robot
/// measurements). Every wait is bounded by `timeout_s` (the error names the missing agents).
/// Throws InputError on an unknown method or 'file' without VERTEX poses (naming `source`).
/// `early` (agent 0, chordal only; may be null): the whole graph's chordal solve started
/// before the stage, used when the gathered graph is the one it solved.
/// `turns`: how many agents run the distributed initialisation's local solve at once
/// (runtime/setup_turns.hpp; every agent of the run must pass the same max_at_once). The
/// waits that span other agents' turns are bounded by `timeout_s` per turn.
InitializationResult run_initialization_stage(
    const RobotShare& share, std::uint32_t self, std::uint32_t num_agents,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::string& method, const std::string& source, ProtocolChannel& channel,
    double timeout_s, EarlyChordal* early = nullptr, const SetupTurnOptions& turns = {});

/// Two stages back to back on one inbox (a robust run's two candidate starts: `method` on
/// `share`, then `second_method` on `second_share`, e.g. the distributed initialization of the
/// known inliers alone, runtime/known_inlier_start.hpp). The second stage's phases are moved by
/// kSecondStagePhaseOffset, so a faster agent's messages of it are kept while this agent is
/// still in the first (two separate calls would drop them).
std::pair<InitializationResult, InitializationResult> run_initialization_stages(
    const RobotShare& share, const RobotShare& second_share, std::uint32_t self,
    std::uint32_t num_agents, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& second_structure,
    const std::string& method, const std::string& second_method, const std::string& source,
    ProtocolChannel& channel, double timeout_s, EarlyChordal* early = nullptr,
    const SetupTurnOptions& turns = {});

}  // namespace tessera::agent
