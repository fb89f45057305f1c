// A CHOLMOD analysis that fails (here: every allocation refused, as when the factor would not
// fit) is an error with its reason, not a crash: Eigen's compute() would dereference the
// missing factor. The centralized solver's first factorizations (the chordal initialization,
// the translations) go through it.

#include "solvers/cholmod_checked.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tessera/certification/certificate.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <tessera/util/resource_error.hpp>
#include <vector>

#include "partition/spectral_layouts.hpp"
#include "partition/work_graph.hpp"
#include "random_graph.hpp"
#include "solvers/supernodal_factor.hpp"
#include "structure_graphs.hpp"

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

// The first `allowed` CHOLMOD allocations (malloc and calloc) succeed, every later one fails:
// a factorization that runs out of memory after its analysis succeeded.
long g_allowed = 0;
void* limited_malloc(std::size_t n) {
  return --g_allowed >= 0 ? std::malloc(n) : nullptr;
}
void* limited_calloc(std::size_t n, std::size_t size) {
  return --g_allowed >= 0 ? std::calloc(n, size) : nullptr;
}
struct LimitedAllocations {
  void* (*saved_malloc)(std::size_t) = SuiteSparse_config.malloc_func;
  void* (*saved_calloc)(std::size_t, std::size_t) = SuiteSparse_config.calloc_func;
  explicit LimitedAllocations(long allowed) {
    g_allowed = allowed;
    SuiteSparse_config.malloc_func = limited_malloc;
    SuiteSparse_config.calloc_func = limited_calloc;
  }
  ~LimitedAllocations() {
    SuiteSparse_config.malloc_func = saved_malloc;
    SuiteSparse_config.calloc_func = saved_calloc;
  }
};

TEST(CholmodChecked, FailedAnalysisOutOfMemoryIsAResourceError) {
  const Eigen::SparseMatrix<double> L = path_laplacian(50);
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  RefusedAllocations refused;
  EXPECT_THROW(cholmod_compute_checked(chol, L, "test factor"), ResourceError);
}

// Eigen's info() after a numeric factorization that ran out of memory says NumericalIssue, which
// the certificate's shift search read as "not positive definite" and shifted on: an error now.
TEST(CholmodChecked, FactorizationOutOfMemoryThrowsInsteadOfLookingIndefinite) {
  Eigen::SparseMatrix<double> L = path_laplacian(300);
  L.coeffRef(0, 0) += 1.0;
  long analysis_allocations = 0;
  {
    Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> probe;
    LimitedAllocations counting(1L << 40);
    probe.analyzePattern(L);
    analysis_allocations = (1L << 40) - g_allowed;
  }
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  std::string message;
  {
    LimitedAllocations limited(analysis_allocations);
    try {
      cholmod_compute_checked(chol, L, "test factor");
    } catch (const ResourceError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("test factor: CHOLMOD's factorization failed (out of memory, 300 x 300"),
            std::string::npos)
      << message << " (after " << analysis_allocations << " allocations of the analysis)";
}

// The centralized certificate's factorizations went through Eigen's compute(): a failed
// analysis (a factor above 2^31 entries, out of memory) crashed the process in it.
TEST(CholmodChecked, CentralizedCertificateReportsAFailedAnalysis) {
  test::RandomGraphSpec spec;
  spec.poses = 40;
  const PoseGraph g = test::random_pose_graph(spec);
  const BlockProblem P = BlockProblem::whole_graph(g.d, g.num_poses, g.measurements);
  const Eigen::MatrixXd X = lift_poses(g.initial, g.d + 1);
  std::string message;
  {
    RefusedAllocations refused;
    try {
      verify_certificate(P, X);
    } catch (const ResourceError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("certificate: CHOLMOD's analysis failed (out of memory"),
            std::string::npos)
      << message;
}

TEST(CholmodChecked, SupernodalFactorOutOfMemoryIsAResourceErrorNamingTheFactor) {
  Eigen::SparseMatrix<double> L = path_laplacian(50);
  L.coeffRef(0, 0) += 1.0;
  const Eigen::SparseMatrix<double> lower = L.triangularView<Eigen::Lower>();
  SupernodalFactor f;
  std::string message;
  {
    RefusedAllocations refused;
    try {
      f.factor(lower);
    } catch (const ResourceError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("SupernodalFactor: CHOLMOD's analysis failed (out of memory, 50 x 50"),
            std::string::npos)
      << message;
  EXPECT_FALSE(f.ok());
}

// The spectral layouts' shift-invert factor is optional: without it (a failed analysis) the
// partitioner has no spectral layouts, as when Lanczos does not converge. It crashed in Eigen.
TEST(CholmodChecked, SpectralLayoutsWithoutAFactorAreNoneInsteadOfACrash) {
  const GraphStructure s = test::grid_structure(60, 8);
  const partition_detail::WorkGraph g = partition_detail::to_work_graph(s);
  const long long lmax = test::uniform_bounds(s, 4, 0.03)[0];
  ASSERT_FALSE(partition_detail::spectral_layouts(g, 4, lmax, {}).empty());
  RefusedAllocations refused;
  EXPECT_TRUE(partition_detail::spectral_layouts(g, 4, lmax, {}).empty());
}

}  // namespace
}  // namespace tessera
