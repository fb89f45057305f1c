#pragma once
// The recurrences of a preconditioned conjugate gradient in the Chronopoulos-Gear form, apart
// from whatever computes its vectors and sums them. Each iteration needs one reduction of
// gamma = <r, z> and delta = <z, H z> (z = P r, w = H z); from them and the previous
// iteration's gamma and alpha follow beta = gamma / gamma_old and
// <p, H p> = delta - beta gamma / alpha_old, then the directions p = z + beta p, q = w + beta q
// (q = H p without a Hessian product) and the step alpha = gamma / <p, H p>. The distributed
// refinement runs two such solves (the Newton step's, distributed/newton_refine.cpp, and the
// trial point's translations), every agent with the same all-agent sums, so with these
// recurrences every agent takes the same scalars. No messages here: the caller exchanges and
// sums.

#include <cmath>

namespace tessera {

/// One iteration's scalars, from PipelinedCg::begin.
struct PipelinedCgIteration {
  bool first = true;   ///< The solve's first iteration: p = z, q = w (no previous direction).
  double gamma = 0.0;  ///< <r, z>.
  double beta = 0.0;   ///< gamma / gamma_old; 0 on the first iteration.
  double pHp = 0.0;    ///< <p, H p> by the recurrence (delta on the first iteration).
  double alpha = 0.0;  ///< gamma / pHp: the step along p (not finite where pHp is 0).

  /// The direction update p = z + beta p, a copy of z on the first iteration. The same for
  /// every vector the CG carries by this recurrence (p, q = H p and their projections).
  template <class Z, class P>
  void update_direction(const Z& z, P& p) const {
    if (first)
      p = z;
    else
      p = z + beta * p;
  }
};

/// The scalar state of one pipelined CG solve: the iteration count and the previous
/// iteration's gamma and alpha. Optionally (the trust-region solve) the norms of the step s and
/// the direction p in the preconditioner's metric, which Steihaug-Toint's boundary test needs:
/// <s, P^-1 s>, <s, P^-1 p>, <p, P^-1 p>, all by recurrence (no extra sum).
class PipelinedCg {
 public:
  /// A new solve from s = 0: the next iteration is the first.
  void restart();
  /// Iterations begun since restart().
  int iterations() const { return iterations_; }
  /// Begins an iteration from its reduction's gamma = <r, z> and delta = <z, H z>: beta, <p, Hp>
  /// and alpha, and counts it.
  PipelinedCgIteration begin(double gamma, double delta);
  /// The iteration's step was taken (s += alpha p, r -= alpha q): its gamma and alpha are the
  /// next iteration's old ones.
  void end(const PipelinedCgIteration& it);

  /// Steihaug-Toint: the preconditioned norms after the direction update of `it`, before
  /// anything else of it: <s, P^-1 p> and <p, P^-1 p> (from gamma on the first iteration).
  void update_norms(const PipelinedCgIteration& it);
  /// <s + alpha p, P^-1 (s + alpha p)> for the iteration's alpha.
  double step_norm2_after(const PipelinedCgIteration& it) const;
  /// tau >= 0 with ||s + tau p||^2 = radius2 in the preconditioner's norm.
  double boundary_step(double radius2) const;
  /// <s, P^-1 s>, once the step was taken (set_step_norm2) or the boundary reached.
  double step_norm2() const { return e_Pe_; }
  void set_step_norm2(double e_Pe) { e_Pe_ = e_Pe; }
  /// <p, P^-1 p> of the current direction.
  double direction_norm2() const { return d_Pd_; }

  /// ||r - alpha q||^2 of this iteration's update with q = w + beta q_old, from the sums
  /// rr = ||r||^2, rw = <r, w>, ww = ||w||^2 and the previous q's rq = <r, q_old>,
  /// wq = <w, q_old>, qq = ||q_old||^2 (the last three 0 on the first iteration): the residual
  /// test right after the update that reached it, without the next reduction.
  static double next_residual_norm2(const PipelinedCgIteration& it, double rr, double rw, double ww,
                                    double rq, double wq, double qq);

 private:
  int iterations_ = 0;
  double gamma_old_ = 0.0, alpha_old_ = 0.0;
  double e_Pe_ = 0.0, e_Pd_ = 0.0, d_Pd_ = 0.0;  // <s,P^-1 s>, <s,P^-1 p>, <p,P^-1 p>
};

}  // namespace tessera
