#pragma once
// Options of the distributed Riemannian staircase: solve at rank r -> certify -> (if a
// negative-curvature direction was found) escape to rank r + 1 -> solve -> certify ...

#include <tessera/certification/distributed_certificate.hpp>
#include <tessera/distributed/saddle_escape.hpp>

namespace tessera {

struct StaircaseOptions {
  /// Highest rank the staircase may climb to (>= the solver's rank; checked by
  /// DistributedOptions::validate when certification is on).
  int max_rank = 10;
  /// Gradient-norm tolerance a rank is refined to when its certificate at the solver's own
  /// tolerance is inconclusive (not certified): Lambda(X) is only as exact as the critical
  /// point, so a failure at a loose point may be an artefact of the residual gradient. Each
  /// rank is solved to the solver's tolerance first; measured on the 17 benchmark graphs the
  /// certificate holds there (docs/distributed-certification.md). Only a certificate that
  /// also fails at this tolerance leads to the saddle escape. 0 = never refine (escape at
  /// once). >= 0. Where the Newton refinement is on (NewtonRefineOptions::enabled) it refines
  /// instead, to its own grad_norm_tol (certified_agent.hpp); this tolerance then only says
  /// that a refinement is wanted (> 0).
  double grad_norm_tol = 1e-4;
  DistributedCertificateOptions certificate;
  SaddleEscapeOptions escape;
  /// Throws InputError naming the bad field.
  void validate() const;
};

}  // namespace tessera
