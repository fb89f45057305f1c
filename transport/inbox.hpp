#pragma once
// Inboxes: where a DDS listener thread drops received messages and where the application
// thread waits for them. Every inbox of a session shares one Mailroom (one mutex and one
// condition variable), so any wait wakes on a new message, on a stop request (signal,
// abort from a peer, lost peer) or on its timeout, whichever comes first. No busy polling.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tessera::transport {

using Seconds = std::chrono::duration<double>;

enum class WaitStatus {
  kReady,    ///< The condition holds (or a message was taken).
  kTimeout,  ///< The timeout passed first.
  kStopped,  ///< The run is stopping (see Mailroom::stop_info()); checked before the condition.
};

/// Why a run stops: the exit code the process should return and a message naming the cause.
struct StopInfo {
  int exit_code = 1;
  std::string reason;
  bool remote =
      false;  ///< Another process asked to stop (ABORT received): no need to tell the others.
  /// ABORT received: the process whose failure started it (agent id, or the coordinator's
  /// id), whoever relayed it, and its cause as that process gave it. Relayed unchanged, so
  /// every process names the first cause and the process that had it.
  std::optional<std::uint32_t> origin;
  std::string cause;
};

class Mailroom {
 public:
  /// Records a stop request (the first one wins) and wakes every waiter.
  void request_stop(int exit_code, const std::string& reason, bool remote = false) {
    request_stop(StopInfo{exit_code, reason, remote, std::nullopt, ""});
  }
  void request_stop(StopInfo info) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!stop_) stop_ = std::move(info);
    }
    cv_.notify_all();
  }
  /// A stop that takes effect after `delay` unless another stop request comes first (used
  /// when a peer leaves cleanly: the ABORT explaining why is usually still on its way).
  void request_stop_after(int exit_code, const std::string& reason, Seconds delay) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!stop_ && !pending_)
        pending_ = Pending{StopInfo{exit_code, reason, false, std::nullopt, ""},
                           std::chrono::steady_clock::now() +
                               std::chrono::duration_cast<std::chrono::nanoseconds>(delay)};
    }
    cv_.notify_all();
  }
  /// Withdraws the pending stop of request_stop_after() if its reason is `reason` and it has
  /// not taken effect yet (a peer that "left" turned out to be replaced by a new participant of
  /// the same process; see Session::replace_participant). Returns whether one was withdrawn.
  bool cancel_pending_stop(const std::string& reason) {
    std::lock_guard<std::mutex> lock(mutex_);
    promote_pending();
    if (stop_ || !pending_ || pending_->info.reason != reason) return false;
    pending_.reset();
    return true;
  }
  std::optional<StopInfo> stop_info() const {
    std::lock_guard<std::mutex> lock(mutex_);
    promote_pending();
    return stop_;
  }
  bool stopped() const { return stop_info().has_value(); }

  /// Waits until `pred()` holds (evaluated with the mailroom locked, so it may read inbox
  /// contents through the *_locked accessors), the run stops, or `timeout` passes.
  WaitStatus wait_for(const std::function<bool()>& pred, Seconds timeout,
                      bool interruptible = true) {
    std::unique_lock<std::mutex> lock(mutex_);
    return wait_locked(lock, pred, timeout, interruptible);
  }

  /// Runs `fn` with the mailroom locked (for listener threads that update shared state).
  template <class Fn>
  auto with_lock(Fn&& fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    return fn();
  }
  /// Wakes every waiter so it re-evaluates its condition (call after with_lock updates).
  void notify() { cv_.notify_all(); }
  /// notify() for a change of what is known about the peers (discovered, lost, authenticated,
  /// endpoint matched, READY ...): also counts it, so a wait whose condition is not a predicate
  /// over locked state ("has anything changed since I looked?", transport/peer_gate.cpp) can
  /// wait for state_changes_locked() to move instead of polling.
  void notify_state_changed() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++state_changes_;
    }
    cv_.notify_all();
  }
  /// Number of notify_state_changed() calls so far; requires the lock (e.g. inside a
  /// wait_for predicate).
  std::uint64_t state_changes_locked() const { return state_changes_; }
  std::uint64_t state_changes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_changes_;
  }

  /// `interruptible` false: a stop request does not end the wait (for leaving cleanly).
  WaitStatus wait_locked(std::unique_lock<std::mutex>& lock, const std::function<bool()>& pred,
                         Seconds timeout, bool interruptible = true) {
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::nanoseconds>(timeout);
    for (;;) {
      promote_pending();
      if (stop_ && interruptible) return WaitStatus::kStopped;
      if (pred()) return WaitStatus::kReady;
      auto until = deadline;
      if (pending_ && interruptible && pending_->at < until) until = pending_->at;
      if (cv_.wait_until(lock, until) == std::cv_status::timeout && until == deadline) {
        promote_pending();
        if (stop_ && interruptible) return WaitStatus::kStopped;
        return pred() ? WaitStatus::kReady : WaitStatus::kTimeout;
      }
    }
  }
  std::mutex& mutex() { return mutex_; }

 private:
  struct Pending {
    StopInfo info;
    std::chrono::steady_clock::time_point at;
  };
  // Requires mutex_ held.
  void promote_pending() const {
    if (pending_ && !stop_ && std::chrono::steady_clock::now() >= pending_->at)
      stop_ = pending_->info;
  }

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  mutable std::optional<StopInfo> stop_;
  mutable std::optional<Pending> pending_;
  std::uint64_t state_changes_ = 0;
};

/// A FIFO of received messages of one type.
template <class T>
class Inbox {
 public:
  explicit Inbox(Mailroom& room) : room_(room) {}
  Inbox(const Inbox&) = delete;
  Inbox& operator=(const Inbox&) = delete;

  /// Appends a message and wakes waiters (called from listener threads) once at least the
  /// wake threshold's count is queued.
  void push(T message) {
    bool wake;
    {
      std::lock_guard<std::mutex> lock(room_.mutex());
      queue_.push_back(std::move(message));
      wake = queue_.size() >= wake_threshold_;
    }
    if (wake) room_.notify();
  }
  /// push() wakes the waiters only once `n` messages are queued (0 counts as 1; 1, the
  /// default, wakes them for every message). For a reader that handles messages in batches
  /// (the coordinator: one round's statuses) and bounds its wait by a timeout anyway; stop
  /// requests and every other inbox still wake it at once.
  void set_wake_threshold(std::size_t n) {
    std::lock_guard<std::mutex> lock(room_.mutex());
    wake_threshold_ = n > 0 ? n : 1;
  }

  /// Same as push() for a caller that already holds the mailroom lock (no wake-up: call
  /// Mailroom::notify() after releasing it).
  void push_locked(T message) { queue_.push_back(std::move(message)); }
  /// Drops every queued message; requires the mailroom lock.
  void clear_locked() { queue_.clear(); }

  /// Waits until `pred(queued messages)` holds, the run stops, or the timeout passes.
  WaitStatus wait_for(const std::function<bool(const std::deque<T>&)>& pred, Seconds timeout) {
    std::unique_lock<std::mutex> lock(room_.mutex());
    return room_.wait_locked(
        lock, [&] { return pred(queue_); }, timeout);
  }

  /// Removes the first queued message satisfying `match` into `*out`, waiting for one to
  /// arrive if needed. Returns kReady when a message was taken.
  WaitStatus take(const std::function<bool(const T&)>& match, Seconds timeout, T* out) {
    std::unique_lock<std::mutex> lock(room_.mutex());
    typename std::deque<T>::iterator found;
    auto pred = [&] {
      for (found = queue_.begin(); found != queue_.end(); ++found)
        if (match(*found)) return true;
      return false;
    };
    WaitStatus status = room_.wait_locked(lock, pred, timeout);
    if (status == WaitStatus::kReady) {
      *out = std::move(*found);
      queue_.erase(found);
    }
    return status;
  }

  /// Takes the first queued message, waiting up to `timeout`.
  WaitStatus take(Seconds timeout, T* out) {
    return take([](const T&) { return true; }, timeout, out);
  }

  /// Removes and returns every queued message satisfying `match` (no waiting).
  std::vector<T> take_all(const std::function<bool(const T&)>& match = [](const T&) {
    return true;
  }) {
    std::lock_guard<std::mutex> lock(room_.mutex());
    std::vector<T> out;
    for (auto it = queue_.begin(); it != queue_.end();) {
      if (match(*it)) {
        out.push_back(std::move(*it));
        it = queue_.erase(it);
      } else {
        ++it;
      }
    }
    return out;
  }

  std::size_t size() const {
    std::lock_guard<std::mutex> lock(room_.mutex());
    return queue_.size();
  }
  /// The queue itself; only while holding the mailroom lock (inside a wait predicate).
  const std::deque<T>& queued_locked() const { return queue_; }

 private:
  Mailroom& room_;
  std::deque<T> queue_;
  std::size_t wake_threshold_ = 1;  // guarded by the mailroom's mutex
};

}  // namespace tessera::transport
