#pragma once
// Internal: balanced partitions read off a spectral embedding of the graph (global layouts).
//
// Multilevel search plus local refinement settles into the nearest local optimum of its start,
// and on mesh-like graphs (sphere2500: a twisted 50 x 50 cylinder grid; torus3D: a 100 x 50
// torus grid) every start it makes leads to the same few rectangular arrangements. Other
// arrangements (bands along the long axis, "a + b" layouts with a bands on one side and b on
// the other, angular sectors around a ring) are far from these in move distance but easy to
// state in coordinates where the graph's large-scale shape is visible: the eigenvectors of its
// smallest nonzero Laplacian eigenvalues (u1 runs along the longest direction, u2 along the
// next one, a ring shows up as a circle in (u1, u2)). This file computes those coordinates and
// cuts them into k blocks of equal weight in several ways; callers refine the results.

#include <string>
#include <vector>

#include "partition/multilevel.hpp"
#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct SpectralLayoutOptions {
  /// Nontrivial Laplacian eigenvectors used as coordinates (the smallest eigenvalues first),
  /// 1..6. Four cover a line, a cylinder (its axis plus the circle around it) and a torus (two
  /// circles, each a degenerate pair).
  int eigenvectors = 4;
  /// Only the layouts with the smallest cut are kept (and refined), at most this many, >= 1.
  int max_layouts = 16;
  /// Arcs of equal angle are tried at this many of their best rotations per set of vertices
  /// (1..8): a single odd vertex (e.g. at a trajectory's start) can make the rotation that
  /// meets a ring's seam look an edge worse before FM fixes it (with 1, sphere2500's structure
  /// stays at 180 in tests/partition_spectral_test.cpp).
  int rotations = 3;
  /// Rotation polish: for the `polish` best refined layouts made of arcs, every set of arcs is
  /// tried at rotation_steps rotations spread over one arc (each rebalanced and FM-refined),
  /// keeping the best. Equal arcs cost the same at any rotation except where their borders
  /// meet a ring's seam (e.g. where a spiral steps to its next turn), which is worth an edge
  /// per side and which FM cannot reach (it would move a whole column). 0..8 and 1..64.
  int polish = 6;
  int rotation_steps = 24;
  /// Layouts are only built for graphs with at most this many vertices (the sparse Cholesky
  /// factorization and the Lanczos iteration grow with n), >= 2.
  int max_vertices = 50000;
  /// ...and for at most this many blocks (the number of "a + b" layouts grows with k), 2..64.
  int max_parts = 8;
  /// Lanczos (Spectra) iteration limit and relative tolerance of the eigenpairs. The layouts
  /// only need the coordinates roughly, so a loose tolerance is enough.
  int lanczos_max_iterations = 300;
  double lanczos_tolerance = 1e-6;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

/// A set of vertices dealt out as arcs around a ring: `order` (sorted by angle) holds blocks
/// first..first+count-1, each a contiguous run of the cyclic order.
struct CyclicSide {
  std::vector<int> order;
  int first = 0;
  int count = 1;
};

/// One candidate layout and how it was built (for traces, tests and the rotation polish).
struct SpectralLayout {
  std::string name;               ///< e.g. "u1 #0", "3+2 u1 / angle u2u4 #01", "rcb".
  std::vector<int> part;          ///< Block per vertex, 0..k-1.
  long long cut = 0;              ///< Its edge cut.
  std::vector<CyclicSide> sides;  ///< Its arcs around rings (empty: slabs only).
};

/// Balanced layouts of g into k blocks from its spectral embedding. Every layout gives each
/// block the vertices of one contiguous range of a sorted order, with block weights as close to
/// total / k as the vertex weights allow (each within one vertex weight). Returns nothing when
/// g has fewer than k + 2 vertices, more than max_vertices, k < 2, k > max_parts, or the
/// eigen-solver does not converge (the caller then simply has no layouts). Deterministic: the
/// same graph gives the same layouts (Spectra starts from a fixed vector).
std::vector<SpectralLayout> spectral_layouts(const WorkGraph& g, int k, long long max_block,
                                             const SpectralLayoutOptions& options);

/// A layout after rebalancing and FM under the search's bounds.
struct RefinedLayout {
  long long cut = 0;
  std::vector<int> part;
  SpectralLayout layout;  ///< As built (its arcs drive the rotation polish).
};

/// The first half of refined_spectral_layouts: every layout rebalanced and FM-refined under ub,
/// best first. It needs nothing from a search, so `highest` runs it beside the search's islands.
std::vector<RefinedLayout> fm_refined_layouts(const WorkGraph& g, int k,
                                              const std::vector<long long>& ub,
                                              const SpectralLayoutOptions& options,
                                              const CycleParams& cycle, Rng& rng);

/// The second half: drops the refined layouts above `worst_useful` (if >= 0), rotation-polishes
/// the rest and V-cycles the `keep` best distinct ones (see refined_spectral_layouts).
std::vector<std::vector<int>> finished_layouts(const WorkGraph& g, int k,
                                               const std::vector<long long>& ub,
                                               const SpectralLayoutOptions& options,
                                               const CycleParams& cycle,
                                               std::vector<RefinedLayout> cands, int keep, Rng& rng,
                                               long long worst_useful = -1);

/// The layouts refined into partitions under ub: each is rebalanced and FM-refined on g (cheap);
/// those whose cut then exceeds `worst_useful` (if >= 0) are dropped; the rest are polished (see
/// SpectralLayoutOptions::polish) and the `keep` best distinct ones are then improved by a V-cycle
/// (guided_cycle with their own blocks as labels) under `cycle`. Returned best first; never more
/// than `keep`.
std::vector<std::vector<int>> refined_spectral_layouts(const WorkGraph& g, int k,
                                                       const std::vector<long long>& ub,
                                                       const SpectralLayoutOptions& options,
                                                       const CycleParams& cycle, int keep, Rng& rng,
                                                       long long worst_useful = -1);

}  // namespace tessera::partition_detail
