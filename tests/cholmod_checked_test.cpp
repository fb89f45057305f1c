// A CHOLMOD analysis that fails (here: every allocation refused, as when the factor would not
// fit) is an error with its reason, not a crash: Eigen's compute() would dereference the
// missing factor. The centralized solver's first factorizations (the chordal initialization,
// the translations) go through it.

#include "solvers/cholmod_checked.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tessera/problem/block_problem.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <vector>

#include "random_graph.hpp"

namespace tessera {
namespace {

void* refuse(std::size_t) {
  return nullptr;
}

// Every CHOLMOD allocation fails while this lives (SuiteSparse's global allocator).
struct RefusedAllocations {
  void* (*saved)(std::size_t) = SuiteSparse_config.malloc_func;
  RefusedAllocations() { SuiteSparse_config.malloc_func = refuse; }
  ~RefusedAllocations() { SuiteSparse_config.malloc_func = saved; }
};

Eigen::SparseMatrix<double> path_laplacian(int n) {
  Eigen::SparseMatrix<double> L(n, n);
  for (int k = 0; k < n; ++k) {
    L.insert(k, k) = k + 1 < n ? 2.0 : 1.0;
    if (k + 1 < n) L.insert(k + 1, k) = L.insert(k, k + 1) = -1.0;
  }
  return L;
}

TEST(CholmodChecked, FailedAnalysisThrowsItsReasonInsteadOfCrashing) {
  const Eigen::SparseMatrix<double> L = path_laplacian(50);
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  std::string message;
  {
    RefusedAllocations refused;
    try {
      cholmod_compute_checked(chol, L, "test factor");
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("test factor: CHOLMOD's analysis failed (out of memory"),
            std::string::npos)
      << message;
}

TEST(CholmodChecked, SuccessfulAnalysisFactorsAsCompute) {
  Eigen::SparseMatrix<double> L = path_laplacian(50);
  L.coeffRef(0, 0) += 1.0;  // grounded: positive definite
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  cholmod_compute_checked(chol, L, "test factor");
  ASSERT_EQ(chol.info(), Eigen::Success);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(50);
  EXPECT_LT((L * chol.solve(b) - b).norm(), 1e-9);
}

TEST(CholmodChecked, ChordalInitializationReportsAFailedAnalysis) {
  test::RandomGraphSpec spec;
  spec.poses = 40;
  const PoseGraph g = test::random_pose_graph(spec);
  std::string message;
  {
    RefusedAllocations refused;
    try {
      chordal_rotations(g);
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("chordal initialization: CHOLMOD's analysis failed"), std::string::npos)
      << message;
}

// The tangent preconditioner whose analysis fails is not usable (the caller keeps its Euclidean
// one), where it would have factored the missing factor later.
TEST(CholmodChecked, TangentPreconditionerWithAFailedAnalysisIsNotUsable) {
  test::RandomGraphSpec spec;
  spec.poses = 40;
  const PoseGraph g = test::random_pose_graph(spec);
  std::vector<std::size_t> owned(g.num_poses);
  std::iota(owned.begin(), owned.end(), std::size_t{0});
  const BlockProblem problem(3, owned, g.measurements);
  RefusedAllocations refused;
  TangentPreconditioner precon(problem, 1e-9, 0, /*supernodal_min_flops=*/1.0);
  EXPECT_FALSE(precon.usable());
}

}  // namespace
}  // namespace tessera
