// The agent's OpenMP setting (launch/serial_openmp.hpp): after serial_openmp(), the calling
// thread's parallel regions are inactive (max-active-levels 0), as CHOLMOD's then run on the
// agent's own thread. Runs in a forked child: the setting is the process's.
#include "launch/serial_openmp.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <vector>

#include "solvers/supernodal_factor.hpp"

namespace {

using tessera::SparseMatrix;

using GetLevels = int (*)();

// OpenMP's max-active-levels on this thread through the loaded runtime; -1 without one.
int max_active_levels() {
  void* symbol = dlsym(RTLD_DEFAULT, "omp_get_max_active_levels");
  return symbol ? reinterpret_cast<GetLevels>(symbol)() : -1;
}

TEST(SerialOpenmp, TheAgentsThreadRunsParallelRegionsAlone) {
  // CHOLMOD brings the OpenMP runtime (a factor here, so that this test links CHOLMOD as the
  // agent does).
  SparseMatrix one(1, 1);
  one.insert(0, 0) = 2.0;
  one.makeCompressed();
  tessera::SupernodalFactor factor;
  ASSERT_TRUE(factor.factor(one));
  ASSERT_NE(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"), nullptr)
      << "no OpenMP runtime loaded: nothing to restrict";
  ASSERT_GT(max_active_levels(), 0);  // parallel regions are active by default
  const pid_t pid = fork();
  if (pid == 0) {
    if (!tessera::launch::serial_openmp()) _exit(3);
    _exit(max_active_levels() == 0 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// After serial_openmp() CHOLMOD's parallel regions run inline on the calling thread (this
// executable's GOMP_parallel, launch/serial_openmp.cpp), and a supernodal factor large enough
// for CHOLMOD to open its regions holds the same bits as with libgomp's teams before.
TEST(SerialOpenmp, InlineRegionsGiveTheFactorOfLibgompsTeams) {
  const int n = 600;
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n; ++j) {
    t.emplace_back(j, j, 8.0 + (j % 7));
    for (int d : {1, 2, 5, 40, 150})
      if (j + d < n) t.emplace_back(j + d, j, -0.5 + 0.01 * ((j * d) % 13));
  }
  SparseMatrix lower(n, n);
  lower.setFromTriplets(t.begin(), t.end());
  tessera::SupernodalFactor before;
  ASSERT_TRUE(before.factor(lower));
  const std::vector<double> want = before.values();
  ASSERT_FALSE(want.empty());
  EXPECT_FALSE(tessera::launch::openmp_regions_run_inline());
  const pid_t pid = fork();
  if (pid == 0) {
    tessera::launch::serial_openmp();
    if (!tessera::launch::openmp_regions_run_inline()) _exit(2);
    tessera::SupernodalFactor after;
    if (!after.factor(lower)) _exit(3);
    _exit(after.values() == want ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
