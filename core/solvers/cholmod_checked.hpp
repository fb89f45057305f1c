#pragma once
// CHOLMOD factorizations that fail with a message instead of a crash or NaNs. Eigen's
// CholmodDecomposition::compute() does not check the analysis: when it returns no factor (a
// factor above CHOLMOD's size limit of 2^31 entries, as the chordal system of the generated
// 1,000,000-pose 3D grid needs, or out of memory), factorize() dereferences the null factor and
// the process dies of SIGSEGV. A numeric factorization that runs out of memory leaves info()
// at NumericalIssue, which callers would read as "not positive definite".
// A resource limit (out of memory, too large) is a ResourceError (util/resource_error.hpp),
// any other CHOLMOD error a std::runtime_error; both say what was factored and why it failed.

#include <Eigen/CholmodSupport>
#include <stdexcept>
#include <string>
#include <tessera/util/resource_error.hpp>

namespace tessera {

/// What CHOLMOD's status `status` (cholmod_common::status, negative = an error) means.
inline std::string cholmod_status_text(int status) {
  switch (status) {
    case CHOLMOD_TOO_LARGE:
      return "the factor is too large for CHOLMOD (more than 2^31 entries)";
    case CHOLMOD_OUT_OF_MEMORY:
      return "out of memory";
    case CHOLMOD_INVALID:
      return "invalid matrix";
    case CHOLMOD_NOT_INSTALLED:
      return "method not installed";
    default:
      return "CHOLMOD status " + std::to_string(status);
  }
}

/// Whether the last analysis of `decomposition` failed (CHOLMOD left no factor). Eigen's
/// analyzePattern() reports Success either way, so its info() cannot tell.
template <class Decomposition>
bool cholmod_analysis_failed(Decomposition& decomposition) {
  return decomposition.cholmod().status < CHOLMOD_OK;
}

/// Throws the error of a failed CHOLMOD step: "WHAT: CHOLMOD's STEP failed (REASON, R x C
/// matrix)", a ResourceError when `status` is a resource limit (out of memory, too large).
[[noreturn]] inline void throw_cholmod_failure(const std::string& what, const std::string& step,
                                               int status, long rows, long cols) {
  const std::string message = what + ": CHOLMOD's " + step + " failed (" +
                              cholmod_status_text(status) + ", " + std::to_string(rows) + " x " +
                              std::to_string(cols) + " matrix)";
  if (status == CHOLMOD_OUT_OF_MEMORY || status == CHOLMOD_TOO_LARGE) throw ResourceError(message);
  throw std::runtime_error(message);
}

/// `decomposition.compute(A)` (analysis, then numeric factorization), except that a failed
/// analysis or a numeric factorization that ends in a CHOLMOD error (out of memory, not "not
/// positive definite", which is a warning) throws (throw_cholmod_failure). A matrix that is
/// not positive definite is left to `decomposition.info()`, as compute() leaves it.
template <class Decomposition, class Matrix>
void cholmod_compute_checked(Decomposition& decomposition, const Matrix& A,
                             const std::string& what) {
  decomposition.analyzePattern(A);
  if (cholmod_analysis_failed(decomposition))
    throw_cholmod_failure(what, "analysis", decomposition.cholmod().status, A.rows(), A.cols());
  decomposition.factorize(A);
  if (decomposition.cholmod().status < CHOLMOD_OK)
    throw_cholmod_failure(what, "factorization", decomposition.cholmod().status, A.rows(),
                          A.cols());
}

}  // namespace tessera
