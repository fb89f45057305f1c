#include "transport/teardown_guard.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstring>

namespace tessera::transport {

namespace {

// State the signal handler reads: written before the handler is installed, so the handler
// only reads plain memory and calls async-signal-safe functions (write, _exit).
volatile std::sig_atomic_t g_exit_code = 1;
char g_abort_note[256];
std::size_t g_abort_note_length = 0;
struct sigaction g_previous_abort;

extern "C" void on_teardown_abort(int) {
  ssize_t ignored = write(STDERR_FILENO, g_abort_note, g_abort_note_length);
  (void)ignored;
  _exit(g_exit_code);
}

}  // namespace

TeardownGuard::TeardownGuard(int exit_code, const std::string& who,
                             std::chrono::duration<double> timeout) {
  g_exit_code = exit_code;
  std::snprintf(g_abort_note, sizeof(g_abort_note),
                "%s: note: Fast DDS aborted after the run's work was done (a known Fast DDS 2.9 "
                "race in its participant lease check); exiting with code %d as intended\n",
                who.c_str(), exit_code);
  g_abort_note_length = std::strlen(g_abort_note);
  struct sigaction sa;
  std::memset(&sa, 0, sizeof(sa));
  sa.sa_handler = on_teardown_abort;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGABRT, &sa, &g_previous_abort);

  watchdog_ = std::thread([this, exit_code, who, timeout] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (cv_.wait_for(lock, timeout, [this] { return done_; })) return;
    std::fprintf(stderr,
                 "%s: note: the DDS teardown did not finish within %.0f s of the run's end (a "
                 "known Fast DDS 2.9 teardown deadlock); exiting with code %d as intended\n",
                 who.c_str(), timeout.count(), exit_code);
    std::fflush(stderr);
    _exit(exit_code);
  });
}

TeardownGuard::~TeardownGuard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  cv_.notify_all();
  watchdog_.join();
  sigaction(SIGABRT, &g_previous_abort, nullptr);
}

}  // namespace tessera::transport
