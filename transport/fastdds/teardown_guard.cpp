#include "transport/fastdds/teardown_guard.hpp"

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace tessera::transport {

namespace {

// State the signal handler reads: written before the handler is installed (or, nested, by
// the guard's own thread while the outer guard's handler stays in place), so the handler only
// reads plain memory and lock-free atomics and calls async-signal-safe functions.
volatile std::sig_atomic_t g_exit_code = 1;
char g_abort_note[256];
std::size_t g_abort_note_length = 0;
const std::atomic<bool>* volatile g_only_once = nullptr;
int g_depth = 0;                    // guards alive (nesting)
struct sigaction g_previous_abort;  // the handler before the outermost guard

extern "C" void on_teardown_abort(int) {
  const std::atomic<bool>* once = g_only_once;
  if (once && !once->load()) {
    // Not covered yet: an abort as without the guard. SIGABRT is blocked inside this handler,
    // so the raised one is delivered, with the previous action, when the handler returns.
    sigaction(SIGABRT, &g_previous_abort, nullptr);
    raise(SIGABRT);
    return;
  }
  ssize_t ignored = write(STDERR_FILENO, g_abort_note, g_abort_note_length);
  (void)ignored;
  _exit(g_exit_code);
}

// With TESSERA_TEARDOWN_STACKS set, a teardown that overran its time prints every thread's
// stack (gdb, where installed) before the process ends: the hang is inside Fast DDS, and only
// its threads' stacks say which of its locks is held. The watchdog is an ordinary thread, so
// forking and waiting here is safe.
void print_thread_stacks() {
  const char* wanted = std::getenv("TESSERA_TEARDOWN_STACKS");
  if (!wanted || !*wanted || access("/usr/bin/gdb", X_OK) != 0) return;
  prctl(PR_SET_PTRACER, PR_SET_PTRACER_ANY, 0, 0, 0);  // Yama: let the child attach to us
  const std::string pid = std::to_string(getpid());
  const pid_t child = fork();
  if (child == 0) {
    dup2(STDERR_FILENO, STDOUT_FILENO);
    execl("/usr/bin/gdb", "gdb", "-nx", "-batch", "-p", pid.c_str(), "-ex", "thread apply all bt",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  if (child > 0) waitpid(child, nullptr, 0);
}

void set_note(const std::string& note) {
  const std::size_t n = std::min(note.size(), sizeof(g_abort_note) - 1);
  std::memcpy(g_abort_note, note.data(), n);
  g_abort_note[n] = '\0';
  g_abort_note_length = n;
}

}  // namespace

TeardownGuard::TeardownGuard(int exit_code, const std::string& who,
                             std::chrono::duration<double> timeout,
                             const std::atomic<bool>* only_once) {
  previous_was_guard_ = g_depth > 0;
  if (previous_was_guard_) {
    previous_exit_code_ = g_exit_code;
    previous_note_.assign(g_abort_note, g_abort_note_length);
    previous_only_once_ = g_only_once;
  }
  char note[256];
  std::snprintf(note, sizeof(note),
                "%s: note: Fast DDS aborted after the run's work was done (a known Fast DDS 2.9 "
                "race in its participant lease check); exiting with code %d as intended\n",
                who.c_str(), exit_code);
  g_only_once = only_once;
  g_exit_code = exit_code;
  set_note(note);
  if (!previous_was_guard_) {
    struct sigaction sa;
    std::memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_teardown_abort;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGABRT, &sa, &g_previous_abort);
  }
  ++g_depth;

  if (timeout.count() <= 0) return;  // aborts only
  watchdog_ = std::thread([this, exit_code, who, timeout] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (cv_.wait_for(lock, timeout, [this] { return done_; })) return;
    std::fprintf(stderr,
                 "%s: note: the DDS teardown did not finish within %.0f s of the run's end (a "
                 "known Fast DDS 2.9 teardown deadlock); exiting with code %d as intended\n",
                 who.c_str(), timeout.count(), exit_code);
    std::fflush(stderr);
    print_thread_stacks();
    _exit(exit_code);
  });
}

TeardownGuard::~TeardownGuard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  cv_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
  --g_depth;
  if (previous_was_guard_) {
    g_only_once = previous_only_once_;
    g_exit_code = previous_exit_code_;
    set_note(previous_note_);
  } else {
    sigaction(SIGABRT, &g_previous_abort, nullptr);
    g_only_once = nullptr;
  }
}

}  // namespace tessera::transport
