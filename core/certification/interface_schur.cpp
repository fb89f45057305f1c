#include "certification/interface_schur.hpp"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace tessera {

InterfaceSchurBlock local_interface_schur(const BlockProblem& problem, const SparseMatrix& lambda,
                                          double shift,
                                          const std::vector<std::size_t>& interface_poses) {
  InterfaceSchurBlock out;
  out.poses = interface_poses;
  const int d = problem.dim();
  const Eigen::Index w = d + 1;
  const auto& owned = problem.owned();
  const Eigen::Index n = w * static_cast<Eigen::Index>(owned.size());
  std::unordered_map<std::size_t, Eigen::Index> slot;
  slot.reserve(owned.size());
  for (std::size_t s = 0; s < owned.size(); ++s)
    slot.emplace(owned[s], static_cast<Eigen::Index>(s));

  // New position of each coordinate: the interior's (fill-reducing order) first, the interface
  // last in interface_poses order, so the factor's trailing block is the Schur complement's.
  const Eigen::Index nG = w * static_cast<Eigen::Index>(interface_poses.size());
  const Eigen::Index nI = n - nG;
  std::vector<Eigen::Index> pos(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < interface_poses.size(); ++k) {
    auto it = slot.find(interface_poses[k]);
    if (it == slot.end()) throw std::runtime_error("interface pose not owned by the block");
    for (Eigen::Index c = 0; c < w; ++c)
      pos[static_cast<std::size_t>(w * it->second + c)] = nI + w * static_cast<Eigen::Index>(k) + c;
  }
  std::vector<Eigen::Index> interior;  // old coordinate of interior index i
  interior.reserve(static_cast<std::size_t>(nI));
  for (Eigen::Index c = 0; c < n; ++c)
    if (pos[static_cast<std::size_t>(c)] < 0) interior.push_back(c);
  std::vector<Eigen::Index> interior_index(static_cast<std::size_t>(n), -1);
  for (std::size_t i = 0; i < interior.size(); ++i)
    interior_index[static_cast<std::size_t>(interior[i])] = static_cast<Eigen::Index>(i);

  const SparseMatrix A = problem.data_matrix() - lambda;
  if (nI > 0) {
    std::vector<Eigen::Triplet<double>> t;
    for (Eigen::Index col = 0; col < n; ++col) {
      const Eigen::Index jc = interior_index[static_cast<std::size_t>(col)];
      if (jc < 0) continue;
      for (SparseMatrix::InnerIterator it(A, col); it; ++it) {
        const Eigen::Index ic = interior_index[static_cast<std::size_t>(it.row())];
        if (ic >= 0) t.emplace_back(ic, jc, 1.0);
      }
    }
    SparseMatrix pattern(nI, nI);
    pattern.setFromTriplets(t.begin(), t.end());
    Eigen::AMDOrdering<int> amd;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
    amd(pattern, perm);
    // perm.indices()(k): the interior index eliminated k-th.
    for (Eigen::Index k = 0; k < nI; ++k)
      pos[static_cast<std::size_t>(interior[static_cast<std::size_t>(perm.indices()(k))])] = k;
  }

  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros() + n));
  for (Eigen::Index col = 0; col < n; ++col) {
    const Eigen::Index pc = pos[static_cast<std::size_t>(col)];
    for (SparseMatrix::InnerIterator it(A, col); it; ++it) {
      const Eigen::Index pr = pos[static_cast<std::size_t>(it.row())];
      if (pr >= pc) t.emplace_back(pr, pc, it.value());
    }
    t.emplace_back(pc, pc, shift);
  }
  SparseMatrix B(n, n);
  B.setFromTriplets(t.begin(), t.end());
  Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> llt(B);
  out.positive_definite = llt.info() == Eigen::Success;
  if (!out.positive_definite) return out;
  const SparseMatrix L = llt.matrixL();
  Eigen::MatrixXd Lgg = Eigen::MatrixXd::Zero(nG, nG);
  for (Eigen::Index col = nI; col < n; ++col)
    for (SparseMatrix::InnerIterator it(L, col); it; ++it)
      if (it.row() >= nI) Lgg(it.row() - nI, col - nI) = it.value();
  out.schur = Lgg * Lgg.transpose();

  // The cut measurements' coupling: S's entries there are Q's (Lambda is pose-diagonal).
  const SparseMatrix& Qnb = problem.neighbor_matrix();
  const auto& neighbors = problem.neighbors();
  for (Eigen::Index col = 0; col < n; ++col) {
    const std::size_t own = owned[static_cast<std::size_t>(col / w)];
    for (SparseMatrix::InnerIterator it(Qnb, col); it; ++it) {
      const std::size_t other = neighbors[static_cast<std::size_t>(it.row() / w)];
      if (own > other || it.value() == 0.0) continue;
      out.rows.push_back(static_cast<Eigen::Index>(own) * w + col % w);
      out.cols.push_back(static_cast<Eigen::Index>(other) * w + it.row() % w);
      out.values.push_back(it.value());
    }
  }
  return out;
}

std::vector<double> encode_interface_schur(const InterfaceSchurBlock& block) {
  std::vector<double> v;
  const Eigen::Index m = block.schur.rows();
  v.push_back(block.positive_definite ? 1.0 : 0.0);
  v.push_back(static_cast<double>(block.poses.size()));
  for (std::size_t p : block.poses) v.push_back(static_cast<double>(p));
  v.push_back(static_cast<double>(m));
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = j; i < m; ++i) v.push_back(block.schur(i, j));
  v.push_back(static_cast<double>(block.values.size()));
  for (std::size_t k = 0; k < block.values.size(); ++k) {
    v.push_back(static_cast<double>(block.rows[k]));
    v.push_back(static_cast<double>(block.cols[k]));
    v.push_back(block.values[k]);
  }
  return v;
}

InterfaceSchurBlock decode_interface_schur(const std::vector<double>& v) {
  auto fail = [] { throw std::runtime_error("certificate: malformed interface block"); };
  std::size_t at = 0;
  auto next = [&]() {
    if (at >= v.size()) fail();
    return v[at++];
  };
  auto count = [&]() {
    const double x = next();
    if (!(x >= 0) || x > static_cast<double>(v.size())) fail();
    return static_cast<std::size_t>(x);
  };
  InterfaceSchurBlock b;
  b.positive_definite = next() != 0.0;
  b.poses.resize(count());
  for (auto& p : b.poses) p = static_cast<std::size_t>(next());
  const auto m = static_cast<Eigen::Index>(count());
  b.schur.resize(m, m);
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = j; i < m; ++i) b.schur(i, j) = b.schur(j, i) = next();
  const std::size_t k = count();
  for (std::size_t e = 0; e < k; ++e) {
    b.rows.push_back(static_cast<Eigen::Index>(next()));
    b.cols.push_back(static_cast<Eigen::Index>(next()));
    b.values.push_back(next());
  }
  if (at != v.size()) fail();
  return b;
}

bool interface_positive_definite(const std::vector<InterfaceSchurBlock>& blocks, int d) {
  const Eigen::Index w = d + 1;
  std::unordered_map<std::size_t, Eigen::Index> index;  // pose -> first coordinate in Sigma
  Eigen::Index M = 0;
  for (const auto& b : blocks) {
    if (!b.positive_definite) return false;
    if (b.schur.rows() != w * static_cast<Eigen::Index>(b.poses.size()))
      throw std::runtime_error("certificate: interface block of the wrong size");
    for (std::size_t p : b.poses) {
      index.emplace(p, M);
      M += w;
    }
  }
  if (M == 0) return true;
  // Sparse: Sigma is dense only within each block's interface; the cut couples few entries
  // (city10000 at N = 5: 152k factor entries against 414k for the dense lower triangle).
  std::vector<Eigen::Triplet<double>> t;
  for (const auto& b : blocks) {
    if (b.poses.empty()) continue;
    const Eigen::Index at = index.at(b.poses.front());
    for (Eigen::Index j = 0; j < b.schur.cols(); ++j)
      for (Eigen::Index i = j; i < b.schur.rows(); ++i)
        t.emplace_back(at + i, at + j, b.schur(i, j));
  }
  for (const auto& b : blocks)
    for (std::size_t k = 0; k < b.values.size(); ++k) {
      auto ri = index.find(static_cast<std::size_t>(b.rows[k] / w));
      auto ci = index.find(static_cast<std::size_t>(b.cols[k] / w));
      if (ri == index.end() || ci == index.end())
        throw std::runtime_error("certificate: coupling outside the interface");
      const Eigen::Index r = ri->second + b.rows[k] % w, c = ci->second + b.cols[k] % w;
      t.emplace_back(std::max(r, c), std::min(r, c), b.values[k]);
    }
  SparseMatrix sigma(M, M);
  sigma.setFromTriplets(t.begin(), t.end());
  Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower> llt(sigma);
  return llt.info() == Eigen::Success;
}

}  // namespace tessera
