#include "launch/launch_children.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace tessera::launch {

namespace {

using Clock = std::chrono::steady_clock;

Child labelled(const ForkSpec& spec, std::size_t k, const std::vector<std::string>& names,
               const std::vector<long>& agents) {
  Child c;
  c.name = names.at(k);
  c.agent = agents.at(k);
  c.log = spec.children[k].log;
  return c;
}

// Starts `child` (fork + exec of its argv) with the process set-up of enter_child_process().
pid_t spawn_one(const ForkChild& child) {
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  if (pid == 0) {
    enter_child_process(child);
    std::vector<char*> args;
    for (const auto& a : child.argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  return pid;
}

int exit_code_of(int status) {
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

std::vector<Child> spawn_exec(const ForkSpec& spec, const std::vector<std::string>& names,
                              const std::vector<long>& agents) {
  std::vector<Child> children;
  for (std::size_t k = 0; k < spec.children.size(); ++k) {
    const ForkChild& f = spec.children[k];
    Child c = labelled(spec, k, names, agents);
    c.pid = spawn_one(f);
    c.running = true;
    children.push_back(c);
    // The coordinator's progress pipe must not stay open in the agents (exec'ed later).
    if (f.stdout_fd > 2) close(f.stdout_fd);
  }
  return children;
}

std::vector<Child> spawn_forked(const std::string& fork_server, ForkSpec spec,
                                const std::vector<std::string>& names,
                                const std::vector<long>& agents, const std::string& server_log,
                                double timeout_s) {
  int pids[2], specs[2];
  if (pipe(pids) != 0 || pipe(specs) != 0) throw std::runtime_error("launch: pipe failed");
  // Only the pids' write end and the spec's read end go to the server.
  fcntl(pids[0], F_SETFD, FD_CLOEXEC);
  fcntl(specs[1], F_SETFD, FD_CLOEXEC);
  spec.pid_fd = pids[1];
  const std::string text = serialize_fork_spec(spec);
  ForkChild server_process;
  server_process.log = server_log;
  server_process.argv = {fork_server, "--spec-fd", std::to_string(specs[0]), "--title-room",
                         std::string(longest_command_line(spec), ' ')};
  // Orphans of our descendants (the server's children once it exits) become our children.
  prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0);
  const pid_t server = spawn_one(server_process);
  close(pids[1]);
  close(specs[0]);
  {
    // A server that died early must not kill launch with SIGPIPE (the server has already
    // been forked, so it keeps the default disposition): it is judged below.
    struct sigaction ignore {};
    struct sigaction previous {};
    ignore.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ignore, &previous);
    for (std::size_t at = 0; at < text.size();) {
      const ssize_t n = write(specs[1], text.data() + at, text.size() - at);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      at += static_cast<std::size_t>(n);
    }
    sigaction(SIGPIPE, &previous, nullptr);
    close(specs[1]);
  }
  for (const ForkChild& f : spec.children)
    if (f.stdout_fd > 2) close(f.stdout_fd);  // the server has its own copy

  std::vector<Child> children;
  std::string pending;
  std::string failure;
  const auto until = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const int left_ms = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count());
    if (left_ms <= 0) {
      failure = "no pid reported within " + std::to_string(timeout_s) + " s";
      break;
    }
    pollfd pfd{pids[0], POLLIN, 0};
    const int ready = poll(&pfd, 1, left_ms);
    if (ready < 0 && errno == EINTR) continue;  // launch's SIGINT handler: judged afterwards
    if (ready <= 0) continue;
    char buf[256];
    const ssize_t n = read(pids[0], buf, sizeof(buf));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // the server closed its end: all reported, or it failed
    pending.append(buf, static_cast<std::size_t>(n));
    for (std::size_t nl; (nl = pending.find('\n')) != std::string::npos;) {
      Child c = labelled(spec, children.size(), names, agents);
      c.pid = static_cast<pid_t>(std::atol(pending.substr(0, nl).c_str()));
      c.running = true;
      pending.erase(0, nl + 1);
      children.push_back(c);
    }
  }
  close(pids[0]);
  // The server exits right after its last report; once it is reaped, every child it forked has
  // been re-parented to us.
  int status = 0;
  int server_code = -1;
  const auto reap_until = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < reap_until) {
    const pid_t r = waitpid(server, &status, WNOHANG);
    if (r == server) {
      server_code = exit_code_of(status);
      break;
    }
    if (r < 0 && errno != EINTR) break;
    usleep(1000);
  }
  if (server_code < 0) {
    kill(server, SIGKILL);
    waitpid(server, &status, 0);
    if (failure.empty()) failure = "it did not exit after starting the processes";
  }
  prctl(PR_SET_CHILD_SUBREAPER, 0, 0, 0, 0);
  if (failure.empty() && server_code != 0)
    failure = "it exited with code " + std::to_string(server_code);
  if (failure.empty() && children.size() != spec.children.size())
    failure = "it reported " + std::to_string(children.size()) + " of " +
              std::to_string(spec.children.size()) + " processes";
  if (!failure.empty()) {
    for (Child& c : children) kill(c.pid, SIGKILL);
    reap(children, true);
    throw std::runtime_error("launch: the fork server (" + fork_server + ") failed: " + failure +
                             "\n" + tail_of(server_log, 10));
  }
  return children;
}

void reap(std::vector<Child>& children, bool block) {
  for (auto& c : children) {
    if (!c.running) continue;
    int status = 0;
    if (waitpid(c.pid, &status, block ? 0 : WNOHANG) == c.pid) {
      c.running = false;
      c.code = exit_code_of(status);
    }
  }
}

bool any_running(const std::vector<Child>& children) {
  for (const auto& c : children)
    if (c.running) return true;
  return false;
}

void stop_all(std::vector<Child>& children, double grace_s) {
  for (auto& c : children)
    if (c.running) kill(c.pid, SIGINT);
  const auto until = Clock::now() + std::chrono::duration<double>(grace_s);
  while (any_running(children) && Clock::now() < until) {
    reap(children, false);
    usleep(20000);
  }
  for (auto& c : children)
    if (c.running) {
      kill(c.pid, SIGKILL);
      std::fprintf(stderr,
                   "tessera launch: %s did not stop within %.0f s of SIGINT: killed (SIGKILL); "
                   "its shared-memory files may remain in /dev/shm (`fastdds shm clean`)\n",
                   c.name.c_str(), grace_s);
    }
  reap(children, true);
}

std::string tail_of(const std::string& path, std::size_t max_lines) {
  std::ifstream f(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);) lines.push_back(l);
  std::string out;
  for (std::size_t k = lines.size() > max_lines ? lines.size() - max_lines : 0; k < lines.size();
       ++k)
    out += "    " + lines[k] + "\n";
  return out;
}

std::vector<std::string> notes_of(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> notes;
  for (std::string l; std::getline(f, l);)
    if (l.find(": note: ") != std::string::npos) notes.push_back(l);
  return notes;
}

}  // namespace tessera::launch
