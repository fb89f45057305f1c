#pragma once
// Options of the distributed Riemannian staircase: solve at rank r -> certify -> (if a
// negative-curvature direction was found) escape to rank r + 1 -> solve -> certify ...

#include "certification/distributed_certificate.hpp"
#include "distributed/saddle_escape.hpp"

namespace tessera {

struct StaircaseOptions {
  /// Highest rank the staircase may climb to (>= the solver's rank; checked by
  /// DistributedOptions::validate when certification is on).
  int max_rank = 10;
  /// Gradient-norm tolerance of the solve stages when certifying (the smaller of this and
  /// the solver's own tolerance). Lambda(X) is only as exact as the critical point: at
  /// ||grad f|| = 0.01 lambda_min(S) is perturbed by about the gradient's size, far above
  /// eta (see docs/distributed-certification.md). 0 = use the solver's tolerance. >= 0.
  double grad_norm_tol = 1e-4;
  DistributedCertificateOptions certificate;
  SaddleEscapeOptions escape;
  /// Throws InputError naming the bad field.
  void validate() const;
};

}  // namespace tessera
