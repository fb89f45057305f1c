// The guard around deleting a DDS participant at exit (transport/fastdds/teardown_guard.hpp): Fast
// DDS 2.9 was seen to abort (assertion in PDP.cpp) or deadlock (DDS Security) in there after the
// run's work was done. While armed, an abort or a teardown that overruns its bound ends the
// process with the exit code it was about to return; disarmed, nothing changes. Each case
// runs in a forked child (no participant needed: the failures are simulated).

#include "transport/fastdds/teardown_guard.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>

namespace {

using tessera::transport::TeardownGuard;

// Runs `body` in a child; returns its exit status as `exit code` or 128 + signal.
int in_child(const std::function<void()>& body) {
  const pid_t pid = fork();
  if (pid == 0) {
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(TeardownGuard, AnAbortDuringTeardownExitsWithTheIntendedCode) {
  EXPECT_EQ(in_child([] {
              TeardownGuard guard(3, "test", std::chrono::seconds(10));
              std::abort();  // what Fast DDS's failed assertion does
            }),
            3);
  // An abort from another thread (Fast DDS's event thread in the real case).
  EXPECT_EQ(in_child([] {
              TeardownGuard guard(0, "test", std::chrono::seconds(10));
              std::thread([] { std::abort(); }).join();
            }),
            0);
}

TEST(TeardownGuard, ATeardownThatHangsEndsAfterTheBound) {
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(in_child([] {
              unsetenv("TESSERA_TEARDOWN_STACKS");  // the suite sets it; no stacks here
              TeardownGuard guard(4, "test", std::chrono::milliseconds(200));
              std::this_thread::sleep_for(std::chrono::seconds(30));  // a deadlocked teardown
            }),
            4);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(TeardownGuard, ATeardownThatFinishesChangesNothing) {
  EXPECT_EQ(in_child([] {
              { TeardownGuard guard(5, "test", std::chrono::seconds(10)); }
              _exit(7);  // the process's own exit code stands
            }),
            7);
  // Disarmed: an abort afterwards is an abort again (the previous handler is back).
  EXPECT_EQ(in_child([] {
              { TeardownGuard guard(5, "test", std::chrono::seconds(10)); }
              std::abort();
            }),
            128 + SIGABRT);
}

// The agent's cover from the coordinator's FINISHED on (cli/session_process.cpp): an abort
// counts as the end of a finished run only once the flag is set; before, it is an abort.
TEST(TeardownGuard, ACoverOnAFlagHoldsOnlyOnceTheFlagIsSet) {
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{false};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              std::thread([] { std::abort(); }).join();
            }),
            128 + SIGABRT);
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{false};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              std::thread([&] { finished = true; }).join();  // the listener, on FINISHED
              std::thread([] { std::abort(); }).join();
            }),
            0);
  // Without a time bound the cover never ends the process on its own.
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{true};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              std::this_thread::sleep_for(std::chrono::milliseconds(300));
              _exit(6);
            }),
            6);
}

// The participant's deletion is guarded inside the agent's cover: the inner guard takes over
// (its exit code, unconditionally), and the outer one holds again after it.
TEST(TeardownGuard, GuardsNestAndTheOuterOneHoldsAgainAfterTheInner) {
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{false};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              TeardownGuard deletion(1, "test", std::chrono::seconds(10));
              std::abort();
            }),
            1);
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{false};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              { TeardownGuard deletion(1, "test", std::chrono::seconds(10)); }
              std::abort();  // the cover again, its flag not set: an abort
            }),
            128 + SIGABRT);
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{true};
              TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
              { TeardownGuard deletion(1, "test", std::chrono::seconds(10)); }
              std::abort();
            }),
            0);
  // Both gone: the previous handler (the default) is back.
  EXPECT_EQ(in_child([] {
              std::atomic<bool> finished{true};
              {
                TeardownGuard cover(0, "test", std::chrono::seconds(0), &finished);
                TeardownGuard deletion(1, "test", std::chrono::seconds(10));
              }
              std::abort();
            }),
            128 + SIGABRT);
}

}  // namespace

// With TESSERA_TEARDOWN_STACKS set, the overrun's note is followed by every thread's stack, so
// a teardown hang inside Fast DDS seen once in a test suite shows which lock it waited on.
TEST(TeardownGuard, AnOverrunPrintsEveryThreadsStackWhenAsked) {
  if (access("/usr/bin/gdb", X_OK) != 0) GTEST_SKIP() << "gdb is not installed";
  const std::string log = testing::TempDir() + "teardown_guard_stacks.log";
  EXPECT_EQ(in_child([&log] {
              setenv("TESSERA_TEARDOWN_STACKS", "1", 1);
              if (!std::freopen(log.c_str(), "w", stderr)) _exit(99);
              TeardownGuard guard(4, "test", std::chrono::milliseconds(200));
              std::this_thread::sleep_for(std::chrono::seconds(60));  // a deadlocked teardown
            }),
            4);
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("teardown did not finish"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("nanosleep"), std::string::npos) << text.str();
  std::remove(log.c_str());
}
