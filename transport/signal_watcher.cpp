#include "transport/signal_watcher.hpp"

#include <pthread.h>

#include <csignal>
#include <cstdlib>

namespace tessera::transport {

namespace {

// SIGUSR2 only wakes the watcher thread for shutdown.
sigset_t watched_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR2);
  return set;
}

}  // namespace

SignalWatcher::SignalWatcher() {
  sigset_t set = watched_signals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void SignalWatcher::start(std::function<void(int)> on_signal) {
  thread_ = std::thread([on_signal = std::move(on_signal)] {
    sigset_t set = watched_signals();
    bool handled = false;
    for (;;) {
      int signo = 0;
      if (sigwait(&set, &signo) != 0) continue;
      if (signo == SIGUSR2) return;
      if (handled) std::_Exit(exit_code_for_signal(signo));  // impatient second signal
      handled = true;
      on_signal(signo);
    }
  });
}

SignalWatcher::~SignalWatcher() {
  stop();
}

void SignalWatcher::stop() {
  if (thread_.joinable()) {
    pthread_kill(thread_.native_handle(), SIGUSR2);
    thread_.join();
  }
}

int exit_code_for_signal(int signo) {
  return 128 + signo;
}

}  // namespace tessera::transport
