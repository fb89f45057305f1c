#pragma once
// Exact solves with the Newton refinement's Riemannian Hessian by substructuring
// (non-overlapping domain decomposition), for its conjugate gradient's preconditioner.
//
// In tangent coordinates (tangent_preconditioner.hpp: p = d(d+1)/2 a pose, rank d) the Hessian
// H = J^T 2 (Q - Lambda) J has the graph's pattern; Lambda (the first-order multipliers) is pose
// diagonal, so H couples two blocks only through the cut measurements, which join interface
// poses (poses with a cut measurement). Each block orders its interior first (pose-level AMD)
// and its interface last and factors its diagonal block, A_bb = L L^T; with y = L^-1 J^T r:
//   Sigma u = rhat,  Sigma = blockdiag_b(L_GG L_GG^T) + (the cut's coupling blocks),
//   rhat_b = L_GG y_G (the interface's Schur-reduced residual),
//   x_b = L^-T [y_I ; L_GG^T u_b],  z = J x   (= H^-1 r).
// Both factors are CHOLMOD's supernodal LL^T (solvers/supernodal_factor.hpp), each analysed
// once (their patterns do not change from point to point), and with an InterfaceAnalysisStore
// once per pattern across the refinements of a run (below). Against Eigen's simplicial LDL^T
// (blocks) and LL^T (Sigma, AMD at every factorization), on city10000 at N = 5 (909 interface
// coordinates, two points, in process; callgrind): the refinement 4.57 -> 1.46 billion
// instructions, Sigma's assembly and factorizations 2.81 -> 0.52 (27.9 Mflop each, 151,785
// entries in L), the blocks' factors and Schur complements 1.38 -> 0.59.
// Sigma is as large as the team's interface (ais2klinik at N = 5: 102 coordinates, city10000
// 909). By default (NewtonRefineOptions::SigmaFactoring::kShipSolves) agent 0 alone receives the
// Schur complements and coupling blocks, factors Sigma and solves with it: the others take their
// segment of each solve (back_own(), adopt_remote_sigma()). Otherwise every agent factors the
// same Sigma from the same bits in id order (or one agent does and the others take its
// factor's values: sigma_values(), import_sigma(); SigmaFactoring::kShipFactor).
// Applying the preconditioner then needs the team's rhat, which is linear in r: CG carries it
// by its recurrences (rhat of H z rides in the iteration's all-agent sum), so a CG iteration is
// still one exchange and one sum (newton_refine.cpp).
//
// Sigma is singular along the problem's gauge (a global rigid motion leaves f unchanged): the
// team's first interface pose is held fixed (grounded, as the translation Sigma of
// translation_interface_solve.hpp), so the preconditioner is the inverse of H restricted to
// the tangent vectors that leave that pose in place (zero there): symmetric positive
// semidefinite, exact on that subspace, where H is positive definite near a nondegenerate
// minimiser. The refinement's CG then solves the Newton equation of the cost with that pose
// fixed (it zeroes the pose's residual, grounded_pose()). Away from a minimiser the grounded
// Sigma may still be slightly indefinite: it is factored with a shift eta I, eta relative to
// its largest diagonal entry, raised on failure; where grounding fails (a disconnected
// interface), Sigma + eta I, the inverse of H + eta P_Gamma.

#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/newton_refine_options.hpp>
#include <tessera/problem/block_problem.hpp>
#include <vector>

namespace tessera {

/// Tangent coordinates of the team's interface at rank `dim` (d(d+1)/2 a pose with a cut
/// measurement): the size of Sigma, known from the layout alone, so every agent computes the same.
Eigen::Index interface_tangent_coordinates(const BlockLayout& layout, int dim);

/// Whether `r` (enabled, `--refine auto`, interface solves on, no coarse space) hands the rounds
/// over to the refinement early on `layout`: the team's interface in tangent coordinates fits
/// r.interface_max_coordinates. From the layout alone, so every agent decides the same
/// (CertifiedAgent's early hand-over, GNC's Newton steps).
bool interface_fits(const NewtonRefineOptions& r, const BlockLayout& layout, int dim);

/// An agent's interface-solve factors with their symbolic analyses (orderings, supernodes) and
/// their matrices' layouts, as one InterfaceSolve leaves them (interface_solve.cpp).
struct InterfaceFactors;

/// Where the refinements of a run keep each agent's InterfaceFactors from one InterfaceSolve to
/// the next (NewtonRefineOptions::analyses). Why: GNC's weighted solves are one refinement each,
/// and each built its block's factor and Sigma's analysis afresh on patterns that mostly repeat
/// (intel, 25 % random outliers: Sigma's analyses were half of its 1.65 G instructions). An
/// InterfaceSolve takes its agent's factors and gives them back when it ends; a factor whose
/// matrix has the pattern it was analysed on factors numerically only, the same factor to the
/// bit, and one with another pattern is analysed again. Agents are keyed by id (in process
/// every agent's refinements share one store); take and give are locked.
class InterfaceAnalysisStore {
 public:
  InterfaceAnalysisStore();
  ~InterfaceAnalysisStore();
  InterfaceAnalysisStore(const InterfaceAnalysisStore&) = delete;
  InterfaceAnalysisStore& operator=(const InterfaceAnalysisStore&) = delete;
  /// Agent `id`'s factors, removed from the store (fresh ones where it holds none).
  std::unique_ptr<InterfaceFactors> take(int id);
  void give(int id, std::unique_ptr<InterfaceFactors> factors);

 private:
  std::mutex mutex_;
  std::map<int, std::unique_ptr<InterfaceFactors>> held_;
};

class InterfaceSolve {
 public:
  /// `problem`: agent `id`'s block; `layout`: the team's. Builds the ordering (no values).
  /// `store` (may be null): where the factors come from and go back to (InterfaceAnalysisStore).
  InterfaceSolve(const BlockProblem& problem, const BlockLayout& layout, int id,
                 std::shared_ptr<InterfaceAnalysisStore> store = nullptr);
  ~InterfaceSolve();
  InterfaceSolve(const InterfaceSolve&) = delete;
  InterfaceSolve& operator=(const InterfaceSolve&) = delete;

  /// Tangent coordinates of the team's interface (the size of Sigma and of rhat).
  Eigen::Index team_size() const;
  /// This block's first coordinate in the team's interface vector, and its count.
  Eigen::Index offset() const;
  Eigen::Index size() const;
  /// Block b's first coordinate in the team's interface vector, and its count.
  Eigen::Index block_offset(int b) const;
  Eigen::Index block_size(int b) const;

  /// Factors the block's Hessian block at X (rank d: d rows, the block's poses), Xn (the
  /// neighbours' poses, rank d) and egrad (the full Euclidean gradient at X, neighbour terms
  /// included). Returns this block's share of Sigma as message values (flag, Schur complement,
  /// couplings). Where A_bb is not positive definite, A_bb without the multiplier term
  /// (flag 2; 1 with it); the flag is 0 when neither is.
  std::vector<double> factor(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                             const Eigen::MatrixXd& egrad);
  /// factor() at another point (a trial point) into a second factor, leaving the current one
  /// and Sigma's in use; commit_pending() makes it the current one (Sigma then due again).
  std::vector<double> factor_pending(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                     const Eigen::MatrixXd& egrad);
  void commit_pending();
  /// Every block's factor() values in id order: assembles Sigma and factors Sigma + eta I with
  /// eta = each of `relative_shifts` in turn times its largest diagonal entry. False (and the
  /// solve unusable) when a block's flag is 0 or no shift gives a positive definite factor.
  bool assemble(const std::vector<const std::vector<double>*>& blocks,
                const std::vector<double>& relative_shifts);
  /// Sigma's factor after an assemble(), as message values for import_sigma() on the other
  /// agents: 1, grounded, the relative shift, then the factor's values (SupernodalFactor::
  /// values()); {0} where the last assemble() failed.
  std::vector<double> sigma_values() const;
  /// Takes another agent's sigma_values() from the same shares as this agent's own assemble()
  /// would factor them, to the bit, without assembling or factoring: true where this agent's
  /// Sigma factor was last analysed on the same pattern (grounded or not); false otherwise (and
  /// where that factor failed), leaving assemble() to be called.
  bool import_sigma(const double* values, std::size_t count);
  /// Sigma factored on another agent (NewtonRefineOptions::SigmaFactoring::kShipSolves): this agent
  /// takes solves with it as that agent's solve() segments, so it records only how it was factored
  /// (grounded or not) for grounded_pose() and back_own(). Cleared by the next factor().
  void adopt_remote_sigma(bool grounded);
  /// Whether the last assemble() (or adopt_remote_sigma()) grounded Sigma.
  bool grounded() const;
  /// u = (Sigma + eta I)^-1 rhat, the team's (team_size() entries; grounded: 0 at the held
  /// pose, rhat there not read), from this agent's own factor (after a successful assemble()).
  Eigen::VectorXd solve(const Eigen::VectorXd& rhat) const;
  /// The shift the last assemble() factored with (relative), 0 before.
  double shift() const;
  /// Symbolic analyses this solve ran (its block's factors and Sigma's, grounded or not): one
  /// per pattern its factors did not hold already.
  int analyses() const;
  /// The held pose, where the last assemble() grounded Sigma and this block owns the team's
  /// first interface pose: its local index (back() is zero there, whatever the residual);
  /// -1 on the other blocks and without grounding.
  Eigen::Index grounded_pose() const;

  /// y = L^-1 P J^T v (v: a tangent vector at X, d rows), the block's forward solve (`pending`:
  /// with the factor_pending() one, X its point).
  void forward(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v, Eigen::VectorXd& y,
               bool pending = false) const;
  /// The block's rhat from y: L_GG y_G, added into team (team_size() entries) at offset()
  /// (`pending`: the factor_pending() one's L_GG).
  void add_interface(const Eigen::VectorXd& y, double* team, bool pending = false) const;
  /// z = J P^T L^-T [y_I ; L_GG^T u_b], u = (Sigma + eta I)^-1 rhat (rhat: the team's,
  /// team_size() entries; grounded: u and z are 0 at the held pose and rhat there is not
  /// read): the preconditioned vector, a tangent vector at X.
  Eigen::MatrixXd back(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                       const Eigen::VectorXd& rhat) const;
  /// back() from this block's own segment of u (size() entries from u_own: solve()'s
  /// entries [offset(), offset() + size())), wherever Sigma was factored.
  Eigen::MatrixXd back_own(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                           const double* u_own) const;

 private:
  std::vector<double> factor_impl(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                  const Eigen::MatrixXd& egrad, bool multipliers, bool pending);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera
