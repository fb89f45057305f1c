#pragma once
// Exact elimination of the translations from the centralized lifted problem (as SE-Sync does
// it), applied to iterates of the explicit-translation solver instead of to the problem.
//
// For fixed Stiefel blocks Y_i, f is a convex quadratic in the translations p_i, minimised by
// one weighted-Laplacian solve (r right-hand sides, one sparse Cholesky factor reused for
// every call). Replacing the translations of each trial point by that minimiser makes the
// trust region evaluate f_red(Y) = min_p f(Y, p), the cost of SE-Sync's rotation-only problem:
// - the step's model is unchanged (at a point with optimal translations the gradient has no
//   translation part, and the preconditioned CG already moves translations with the rotations);
// - the actual decrease can only grow (the refined point costs at most the retracted one),
//   which matters on long chains: a small rotation of one pose swings every pose behind it, and
//   the linear translation part of the step misses that swing by O(angle^2 x lever arm). On
//   ais2klinik this is what kept rejecting trust-region steps.
// The problem's variables and interface stay those of BlockProblem (the distributed solvers
// share them); only the centralized solver refines its points.

#include <Eigen/Core>
#include <memory>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera {

class TranslationElimination {
 public:
  /// Factors the translation Laplacian of a connected graph with poses 0..num_poses-1.
  /// `simplicial`: no supernodal factorization (no BLAS calls, see chordal_rotations); false:
  /// CHOLMOD chooses. Throws std::runtime_error when the factorization fails (disconnected graph).
  TranslationElimination(int d, std::size_t num_poses, const std::vector<Measurement>& measurements,
                         bool simplicial = false);
  ~TranslationElimination();
  TranslationElimination(const TranslationElimination&) = delete;
  TranslationElimination& operator=(const TranslationElimination&) = delete;

  /// Replaces every translation column p_i of the lifted X (r x (d+1)n) by the minimiser of
  /// f over the translations for X's Stiefel blocks. Pose 0's translation is kept (the cost
  /// does not change under a common shift of all translations), so repeated calls do not drift.
  void optimize_translations(Eigen::MatrixXd& X) const;

 private:
  struct Factor;
  int d_;
  std::size_t n_;
  std::vector<Measurement> edges_;
  std::unique_ptr<Factor> factor_;
};

}  // namespace tessera
