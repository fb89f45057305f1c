#pragma once
// How the coarse terms and motions of the two-level rounds travel (CoarseOptions::gather).
// Gathered (the default): every agent sends its terms to one solver agent only, beside its
// round status; the solver assembles Q_c in agent-id order, solves the small problem once and
// sends each agent just the motions its own poses and its copies of neighbour poses move by
// (its pieces and the pieces their smoothing blends in). One more message step on correction
// rounds; bytes a round grow with N (each term and each answer is about one block's share)
// instead of N^2, and one agent solves instead of all N. The solver is protocol id 0, which
// every layout has: a re-partition among survivors numbers them from 0, a rejoined or
// replacing agent takes the lost agent's id. Since the solver runs the same code on the same
// terms as every agent did all to all, the motions, and so the iterates, are bit-identical.
//
// Both messages are PoseBlockMessages shaped like pose blocks (pose_ids.size() x rank x (dim+1)
// values), so they take the addressed (filtered) paths of pose blocks over DDS, where a status
// would reach every agent's reader, and the terms can ride in the status sample to the relay
// agent, which is the solver.

#include <Eigen/Core>
#include <cstdint>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

/// The agent that gathers the terms and solves the coarse problem.
constexpr int kCoarseSolver = 0;
/// The id of the motions message's last entry, which carries f's decrease.
constexpr std::uint32_t kCoarseDecreaseId = 0xFFFFFFFFu;

/// The coarse unknowns whose motions move agent `agent`'s own poses or its copies of its
/// neighbours' public poses, ascending: with the smoothed space (`space` not null) the
/// aggregates in those poses' weights; with the block space its own block and its adjacent
/// blocks. Computed from what every agent knows (layout, space), so solver and agent agree.
std::vector<int> coarse_unknowns_of(const CoarseSpace* space, const BlockLayout& layout, int agent);

/// Agent `sender`'s coarse terms for the solver: one column of values (one "pose", id 0,
/// rank = the number of terms, dim 0).
PoseBlockMessage coarse_terms_message(int sender, std::uint32_t round, std::uint32_t phase,
                                      std::vector<double> terms);
/// The terms of such a message; throws std::runtime_error ("malformed message") when it is
/// not one.
const std::vector<double>& coarse_terms_of(const ProtocolMessage& message);

/// The solver's answer to one agent: the motions Z = [G c] of `unknowns` as r x (r+1)
/// "poses" (rank r, dim r; pose_ids = the unknowns), then one more "pose" with id
/// kCoarseDecreaseId whose first value is f's decrease. With `applied` false (the correction is
/// not taken): no poses and no values.
PoseBlockMessage coarse_motions_message(int sender, std::uint32_t round, std::uint32_t phase,
                                        const std::vector<int>& unknowns,
                                        const std::vector<Eigen::MatrixXd>& motions,
                                        double decrease, bool applied);

struct ReceivedCoarseMotions {
  bool applied = false;
  double decrease = 0.0;
  /// One per coarse unknown (`count`): the sent ones, [I 0] for the others.
  std::vector<Eigen::MatrixXd> motions;
};

/// Reads the solver's answer for an agent whose unknowns are `expected` (coarse_unknowns_of)
/// out of `count`, at rank r. Throws std::runtime_error ("malformed message") when the ids or
/// sizes do not match.
ReceivedCoarseMotions read_coarse_motions(const ProtocolMessage& message, int r, int count,
                                          const std::vector<int>& expected);

}  // namespace tessera
