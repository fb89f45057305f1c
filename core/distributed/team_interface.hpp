#pragma once
// The team's interface as the substructuring solves lay it out (interface_solve.hpp: p tangent
// coordinates a pose; translation_interface_solve.hpp: one translation row a pose): every
// block's interface poses (interface_poses.hpp), blocks in id order, each one's poses
// ascending, `per_pose` unknowns each, so every agent places the blocks' Schur complements in
// the same Sigma from the layout alone; and one block's own poses with its interface last, the
// order its factor's trailing block (the Schur complement it shares) is in.

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <unordered_map>
#include <vector>

namespace tessera {

struct TeamInterface {
  std::unordered_map<std::size_t, Eigen::Index> first;  ///< Interface pose -> its first unknown.
  std::vector<Eigen::Index> block_offset, block_size;   ///< Per block, in unknowns.
  Eigen::Index size = 0;                                ///< Sigma's dimension.
};

TeamInterface team_interface(const BlockLayout& layout, Eigen::Index per_pose);

/// Block `id`'s poses (`owned`, its layout's order) with the interface last.
struct OwnInterfaceLast {
  /// One per owned pose: interface pose k of the block (ascending ids) at interior + k, every
  /// interior pose -1 (what solvers/interface_last_order.hpp's place_interior_first fills).
  std::vector<Eigen::Index> slot;
  std::vector<Eigen::Index> local;  ///< The interface poses' indices into `owned`, ascending ids.
  Eigen::Index interior = 0;        ///< Poses not on the interface.
};

/// Throws std::logic_error "`who`: interface pose not owned" when the layout's interface of
/// block `id` has a pose outside `owned`.
OwnInterfaceLast own_interface_last(const std::vector<std::size_t>& owned,
                                    const BlockLayout& layout, int id, const std::string& who);

}  // namespace tessera
