#pragma once
// The messages agents exchange during a distributed solve, independent of any transport.
// An in-process driver hands them over directly; the DDS runtime maps each type 1:1 to an
// IDL type (idl/) and back. Fields are plain values so that mapping is mechanical.
//
// Lifted poses travel as flat arrays: pose_ids[k] owns data[k*r*(d+1) .. (k+1)*r*(d+1)),
// the r x (d+1) block [Y_i | p_i] stored column-major.

#include <cstdint>
#include <utility>
#include <variant>
#include <vector>

namespace tessera {

/// Which sequence of the accelerated methods a pose block belongs to.
enum class BlockKind : std::uint8_t { kY = 0, kP = 1, kV = 2 };

/// Public (boundary) poses of one agent's block, for the neighbours that need them.
struct PoseBlockMessage {
  std::uint32_t round = 0;
  std::uint32_t sender = 0;
  /// Protocol step within the round (see distributed/round_protocol.hpp).
  std::uint32_t phase = 0;
  BlockKind kind = BlockKind::kY;
  std::uint32_t rank = 0;  ///< r
  std::uint32_t dim = 0;   ///< d
  std::vector<std::uint32_t> pose_ids;
  std::vector<double> data;
};

/// One agent's scalar contributions to the global reductions of a round, and its votes.
struct RoundStatusMessage {
  std::uint32_t round = 0;
  std::uint32_t sender = 0;
  std::uint32_t phase = 0;       ///< Protocol step within the round (algorithm specific).
  double cost = 0.0;             ///< Contribution to f, every measurement counted once overall.
  double grad_norm_sq = 0.0;     ///< Contribution to ||grad f||^2.
  double block_grad_norm = 0.0;  ///< This block's own gradient norm (greedy selection).
  bool restart_vote = false;
  bool done_vote = false;
  /// Robust (GNC) weights messages only (robust/gnc_messages.hpp): the sender's measurements
  /// whose squared residual is near the bound (RobustOptions::jump_band, the early end's vote);
  /// 0 otherwise.
  std::uint32_t near_bound = 0;
  /// Coarse-correction rounds exchanged all to all (CoarseOptions::gather off) only: this
  /// agent's coarse terms (distributed/coarse_correction.hpp); empty otherwise.
  std::vector<double> coarse;
  /// Robust (GNC) exchanges only (robust/gnc_agent.hpp): measurements by their position in the
  /// input file and their weights, same order; empty otherwise.
  std::vector<std::uint64_t> measurement_ids;
  std::vector<double> weights;
};

using ProtocolMessage = std::variant<PoseBlockMessage, RoundStatusMessage>;

/// A message an agent wants sent: to every agent (broadcast) or to the listed agents.
struct OutgoingMessage {
  ProtocolMessage message;
  bool broadcast = true;
  std::vector<std::uint32_t> recipients;  ///< Used when broadcast is false.
};

/// `message` addressed to one agent only.
inline OutgoingMessage addressed_to(std::uint32_t agent, ProtocolMessage message) {
  OutgoingMessage o;
  o.message = std::move(message);
  o.broadcast = false;
  o.recipients = {agent};
  return o;
}

}  // namespace tessera
