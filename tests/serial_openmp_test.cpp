// The agent's OpenMP setting (launch/serial_openmp.hpp): after serial_openmp(), the calling
// thread's parallel regions are inactive (max-active-levels 0), as CHOLMOD's then run on the
// agent's own thread. Runs in a forked child: the setting is the process's.
#include "launch/serial_openmp.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

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

}  // namespace
