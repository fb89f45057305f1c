#pragma once
// With `tessera launch --agents-yield` (off by default: it did not pay where measured, see
// below), an agent forked by launch's fork server starts below the coordinator's scheduling
// priority and returns to it once it has its assignment (or after a bound), so that the
// coordinator's partition of launch's file, which runs while the agents start and is the in-process
// run's partition (`highest`: two island threads, i.e. both cores of a 2-core host), gets the CPU
// first and the agents' start-up (participant, share, discovery: ~0.07 s of CPU each on
// CSAIL) fills what it leaves. Nothing is faster in total: the change decides who waits
// (docs/dds-runtime.md, "Session 9 (start9)": on a loaded 2-core host the partition got
// ~0.15 s shorter and the agents' discovery ~0.15 s longer).
//
// Two kernel mechanisms, since which one decides depends on the host:
// - autogroup scheduling on (Debian's default): the CPU is shared between sessions, and nice
//   only orders the threads inside one. launch starts its fork server in a session of its own
//   (cli/launch_children.cpp) and the server lowers that session's group once it has forked the
//   agents (lower_autogroup_nice; the coordinator has a session of its own). Raising a group's
//   nice and setting it back to 0 are allowed to any user (the kernel refuses only nice < 0).
// - autogroup off: per-thread nice. Lowered only when it can be restored, i.e. with
//   CAP_SYS_NICE or an RLIMIT_NICE that allows nice 0: an unprivileged process may raise its
//   nice but not lower it again, and an agent left at nice 19 for its rounds would be slower
//   than one never lowered.
// Standalone tessera-agent processes (other hosts, by hand) are never lowered.

#include <memory>
#include <string>

namespace tessera::agent {

struct StartupPriorityOptions {
  /// Nice value of the agents (threads or group) until their assignment. Range 1..19;
  /// default 19 (what launch uses), the lowest: the coordinator's partition then runs as if the
  /// agents were not there, and the agents still get every cycle it leaves (CFS is
  /// work-conserving).
  int nice = 19;
  /// Seconds after the agent's start at which it returns to nice 0 even without an
  /// assignment, so that a loaded host (where nice-19 threads get ~1.5 % of a core against a
  /// nice-0 one) delays the start-up by at most this. Range (0, 60]; default 1.0 (the
  /// assignment of a CSAIL run comes after ~0.6 s idle).
  double bound_s = 1.0;

  /// The bound an agent with participant lease `lease_s` uses: min(bound_s, 0.4 x lease_s).
  /// A lowered agent may get almost no CPU while the partition fills both cores, and its
  /// participant announcements (every lease/5) must not lapse for a whole lease, or the
  /// coordinator reports it lost (seen idle on intel with bound 1.0 s = lease 1.0 s: "lost
  /// agent 3 ... participant lease of 1.0 s expired").
  double bound_for_lease(double lease_s) const;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

/// In launch's fork server, before it forks the agents: lowers the nice of the calling
/// process's autogroup (/proc/self/autogroup) to `nice`. Returns whether it did (false: no
/// autogroup support, or the kernel's rate limit refused the write).
bool lower_autogroup_nice(int nice);

/// In a forked agent before its first thread: lowers this thread's nice to `nice` (every
/// thread created later inherits it) when it can be restored, and records what was lowered
/// (`autogroup`: the fork server lowered this process's group) for restore. Returns whether
/// anything is lowered.
bool enter_startup_priority(const StartupPriorityOptions& o, bool autogroup);

/// True while this process runs lowered (between enter_startup_priority and restore).
bool startup_priority_lowered();

/// Sets every thread of this process, and its autogroup when the fork server lowered it, back
/// to nice 0. Idempotent and thread-safe; a no-op when nothing was lowered. Returns a one-line
/// description of what was restored, for --verbose ("" if nothing).
std::string restore_startup_priority();

/// The bound of StartupPriorityOptions: a thread that restores the priority `bound_s` after
/// construction unless restore_startup_priority ran before. Does nothing when nothing is
/// lowered. Must be constructed after the process's signal mask is set (SignalWatcher), since
/// its thread inherits it. Joined by the destructor.
class StartupPriorityBound {
 public:
  explicit StartupPriorityBound(double bound_s);
  ~StartupPriorityBound();
  StartupPriorityBound(const StartupPriorityBound&) = delete;
  StartupPriorityBound& operator=(const StartupPriorityBound&) = delete;

 private:
  struct State;
  std::unique_ptr<State> state_;  // null when nothing was lowered
};

}  // namespace tessera::agent
