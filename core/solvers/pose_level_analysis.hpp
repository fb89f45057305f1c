#pragma once
// Symbolic analysis of a pose-level pattern (one row and column a pose), the way the tangent
// factors are ordered: CHOLMOD's AMD with postordering, LDL^T, pattern only. It is how both the
// tangent preconditioner and the centralized solver's choice of preconditioner estimate a
// tangent factor's size (each pose's block dense) without assembling it.

#include <cholmod.h>

#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

struct PoseLevelAnalysis {
  bool ok = false;            ///< false when CHOLMOD's analysis failed (nothing else is set)
  double factor_entries = 0;  ///< entries of the pose-level factor, diagonal included (lnz)
  double flops = 0;           ///< flops of its numeric factorization (CHOLMOD's fl)
  std::vector<int> order;     ///< CHOLMOD's postordered Perm, only when asked for
};

/// Analyses `lower` (the pattern's lower triangle with the diagonal; values are ignored by the
/// analysis, which reads the pattern only). With `want_order` the result holds the ordering.
PoseLevelAnalysis analyse_pose_level_pattern(const SparseMatrix& lower, bool want_order);

/// The pose-level pattern of `M` (square, `width` consecutive coordinates a pose): the lower
/// triangle with the diagonal, one entry where any coordinate of pose i meets one of pose j.
/// Values carry no meaning (the analysis reads the pattern only).
SparseMatrix pose_level_pattern(const SparseMatrix& M, int width);

/// A pose ordering (`pose_order[k]`: the pose placed k-th) expanded to the coordinates, each
/// pose's `width` coordinates kept together and in order.
std::vector<int> coordinate_order(const std::vector<int>& pose_order, int width);

/// CHOLMOD's symbolic analysis of `A` (square, `width` consecutive coordinates a pose; its
/// lower triangle is read, the diagonal must be in the pattern) ordered at the pose level:
/// AMD on pose_level_pattern(A), each pose's coordinates kept together, which costs (width)^2
/// times less than AMD on the coordinates; CHOLMOD's own AMD where that analysis fails or the
/// size is not a multiple of `width`. Sets `c`'s ordering fields. Null when CHOLMOD's analysis
/// fails (c.status says why): the caller names the failure.
cholmod_factor* analyse_pose_ordered(const SparseMatrix& A, int width, cholmod_common& c);

}  // namespace tessera
