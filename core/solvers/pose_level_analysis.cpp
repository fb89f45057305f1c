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

SparseMatrix pose_level_pattern(const SparseMatrix& M, int width) {
  if (width <= 0) return SparseMatrix();
  const Eigen::Index m = M.rows() / width;
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index j = 0; j < m; ++j) t.emplace_back(j, j, 1.0);
  for (Eigen::Index col = 0; col < M.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(M, col); it; ++it)
      if (it.row() / width > col / width) t.emplace_back(it.row() / width, col / width, 1.0);
  SparseMatrix B(m, m);
  B.setFromTriplets(t.begin(), t.end());
  return B;
}

std::vector<int> coordinate_order(const std::vector<int>& pose_order, int width) {
  std::vector<int> order(pose_order.size() * static_cast<std::size_t>(width));
  for (std::size_t k = 0; k < pose_order.size(); ++k)
    for (int q = 0; q < width; ++q)
      order[k * static_cast<std::size_t>(width) + static_cast<std::size_t>(q)] =
          pose_order[k] * width + q;
  return order;
}

cholmod_factor* analyse_pose_ordered(const SparseMatrix& A, int width, cholmod_common& c) {
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_GIVEN;
  c.postorder = 1;
  const Eigen::Index n = A.rows();
  const Eigen::Index m = width > 0 ? n / width : 0;
  const PoseLevelAnalysis a = analyse_pose_level_pattern(pose_level_pattern(A, width), true);
  std::vector<int> perm;
  if (a.ok && a.order.size() == static_cast<std::size_t>(m) && m * width == n)
    perm = coordinate_order(a.order, width);
  else
    c.method[0].ordering = CHOLMOD_AMD;
  cholmod_sparse view = Eigen::viewAsCholmod(A.selfadjointView<Eigen::Lower>());
  return cholmod_analyze_p(&view, perm.empty() ? nullptr : perm.data(), nullptr, 0, &c);
}

}  // namespace tessera
