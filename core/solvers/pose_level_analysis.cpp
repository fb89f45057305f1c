#include "solvers/pose_level_analysis.hpp"

#include <Eigen/CholmodSupport>

namespace tessera {

namespace {

// Eigen's CHOLMOD wrapper with access to the factor's ordering.
class SymbolicLdlt : public Eigen::CholmodDecomposition<SparseMatrix, Eigen::Lower> {
 public:
  const cholmod_factor* factor() const { return m_cholmodFactor; }
};

}  // namespace

PoseLevelAnalysis analyse_pose_level_pattern(const SparseMatrix& lower, bool want_order) {
  PoseLevelAnalysis out;
  SymbolicLdlt symbolic;
  symbolic.setMode(Eigen::CholmodLDLt);
  cholmod_common& c = symbolic.cholmod();
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  symbolic.analyzePattern(lower);
  // Eigen reports Success even where CHOLMOD left no factor (out of memory, too large).
  if (symbolic.info() != Eigen::Success || symbolic.factor() == nullptr) return out;
  out.ok = true;
  out.factor_entries = static_cast<double>(c.lnz);
  out.flops = static_cast<double>(c.fl);
  if (want_order) {
    const int* perm = static_cast<const int*>(symbolic.factor()->Perm);
    out.order.assign(perm, perm + lower.rows());
  }
  return out;
}

}  // namespace tessera
