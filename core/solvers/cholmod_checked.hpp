#pragma once
// A CHOLMOD factorization through Eigen's wrapper that fails with a message instead of a crash
// where CHOLMOD's symbolic analysis fails. Eigen's CholmodDecomposition::compute() does not
// check the analysis: when it returns no factor (a factor above CHOLMOD's size limit of 2^31
// entries, as the chordal system of the generated 1,000,000-pose 3D grid needs, or out of
// memory), factorize() dereferences the null factor and the process dies of SIGSEGV.

#include <Eigen/CholmodSupport>
#include <stdexcept>
#include <string>

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

/// `decomposition.compute(A)` (analysis, then numeric factorization), except that a failed
/// analysis throws std::runtime_error "WHAT: CHOLMOD's analysis failed (REASON)". The numeric
/// factorization's outcome is left to `decomposition.info()`, as compute() leaves it.
template <class Decomposition, class Matrix>
void cholmod_compute_checked(Decomposition& decomposition, const Matrix& A,
                             const std::string& what) {
  decomposition.analyzePattern(A);
  const int status = decomposition.cholmod().status;
  if (cholmod_analysis_failed(decomposition))
    throw std::runtime_error(what + ": CHOLMOD's analysis failed (" + cholmod_status_text(status) +
                             ", " + std::to_string(A.rows()) + " x " + std::to_string(A.cols()) +
                             " matrix)");
  decomposition.factorize(A);
}

}  // namespace tessera
