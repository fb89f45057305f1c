#include "launch/supervision.hpp"

#include <poll.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "launch/failure_report.hpp"
#include "runtime/progress_lines.hpp"
#include "transport/fastdds/shm_leftovers.hpp"

namespace tessera::launch {

namespace {

volatile sig_atomic_t g_signal = 0;
void on_signal(int signo) {
  g_signal = signo;
}

// Adds the data segments the running `children` map now to `segments`: a killed process
// cannot remove its own, and only its peers' maps tell its segment apart
// (transport/fastdds/shm_leftovers.hpp).
void note_segments(const std::vector<Child>& children, std::set<std::string>& segments) {
  std::vector<pid_t> pids;
  for (const auto& c : children)
    if (c.running) pids.push_back(c.pid);
  const auto mapped = transport::mapped_segments(pids);
  segments.insert(mapped.begin(), mapped.end());
}

// Reads what the coordinator wrote on the progress pipe; prints the progress lines (unless
// quiet) and the summary when it is announced. Returns false once the pipe is closed.
bool stream_progress(const SupervisionOptions& o, std::string& pending, SupervisionOutcome& out) {
  pollfd pfd{o.progress_fd, POLLIN, 0};
  if (poll(&pfd, 1, 50) <= 0) return true;
  char buf[4096];
  const ssize_t n = read(o.progress_fd, buf, sizeof(buf));
  if (n <= 0) return false;
  pending.append(buf, static_cast<std::size_t>(n));
  for (std::size_t nl; (nl = pending.find('\n')) != std::string::npos;) {
    const std::string line = pending.substr(0, nl);
    pending.erase(0, nl + 1);
    if (line == coordinator::kSummaryWrittenLine) {
      // The result is known: show it now, not after every process has left.
      if (const auto text = read_summary(o.summary)) {
        print_summary(*text);
        out.summary = *text;
        out.summary_printed = true;
      }
      continue;
    }
    if (!o.quiet) std::printf("%s\n", line.c_str());
  }
  std::fflush(stdout);
  return true;
}

// Judges the processes that have ended since the last call; sets out.failure on the first
// failure.
void judge_ended(std::vector<Child>& children, const SupervisionOptions& o,
                 SupervisionOutcome& out) {
  const bool coordinator_done = !children[0].running && children[0].code == 0;
  for (auto& c : children) {
    if (c.running || c.judged) continue;
    c.judged = true;
    // A note means a teardown guard ended it (transport/fastdds/teardown_guard.hpp): with its code,
    // but from inside Fast DDS, so its files stay like a failed process's.
    if (!notes_of(c.log).empty()) out.guard_ended = true;
    if (c.code != 0 || out.guard_ended) note_segments(children, out.run_segments);
    const ExitVerdict v = judge_exit(o.loss, c.agent, c.code, coordinator_done);
    c.lost = v.lost;
    if (!v.notice.empty()) std::fprintf(stderr, "tessera launch: %s\n", v.notice.c_str());
    if (!v.failure.empty() && out.failure.empty()) {
      out.failure = v.failure;
      out.exit_code = 1;
    }
  }
}

// After a failure: every process stops, and the failed ones' log tails are shown.
void stop_after_failure(std::vector<Child>& children, SupervisionOutcome& out) {
  std::fprintf(stderr, "tessera launch: %s\n", out.failure.c_str());
  // The others notice a lost or aborting peer themselves (within ~2 s): give them time to
  // stop on their own and say why, then ask (SIGINT) and finally force (SIGKILL).
  if (out.exit_code != 130) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
    while (any_running(children) && std::chrono::steady_clock::now() < until) {
      reap(children, false);
      usleep(20000);
    }
  }
  note_segments(children, out.run_segments);  // stop_all may have to SIGKILL some of them
  stop_all(children, out.exit_code == 130 ? 5.0 : 3.0);
  std::vector<FailedProcess> failed;
  for (const auto& c : children)
    if (c.code != 0 && c.code != 130 && c.code != 143)
      failed.push_back({c.name, c.agent, c.code, tail_of(c.log, 6)});
  for (const FailureGroup& g : group_failures(failed))
    std::fprintf(stderr, "  %s (exit %d):\n%s", g.label().c_str(), g.members.front()->code,
                 g.members.front()->tail.c_str());
  if (out.exit_code == 1) out.exit_code = exit_code_after_failure(failed);
}

}  // namespace

StopSignals::StopSignals() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old_int_);
  sigaction(SIGTERM, &sa, &old_term_);
  g_signal = 0;
}

StopSignals::~StopSignals() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
}

int StopSignals::stop_requested() {
  return g_signal;
}

std::optional<std::string> read_summary(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void print_summary(const std::string& text) {
  std::printf("summary:\n%s", text.c_str());
  std::fflush(stdout);
}

SupervisionOutcome supervise(std::vector<Child>& children, const SupervisionOptions& o) {
  SupervisionOutcome out;
  std::string pending;
  bool pipe_open = true;
  for (;;) {
    if (pipe_open)
      pipe_open = stream_progress(o, pending, out);
    else
      usleep(5000);  // the end of a run: the agents' exits are reaped within 5 ms
    reap(children, false);
    if (const int signo = StopSignals::stop_requested()) {
      out.failure = std::string("interrupted (") + (signo == SIGINT ? "SIGINT" : "SIGTERM") +
                    "): stopping every process";
      out.exit_code = 130;
      break;
    }
    judge_ended(children, o, out);
    if (!out.failure.empty()) break;
    if (!any_running(children)) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - o.start).count() >
        o.timeout_s) {
      out.failure = "time limit of " + std::to_string(o.timeout_s) + " s reached";
      out.exit_code = 1;
      break;
    }
  }
  close(o.progress_fd);
  if (!out.failure.empty()) stop_after_failure(children, out);
  return out;
}

}  // namespace tessera::launch
