#include "launch/fork_spec.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <tessera/util/input_error.hpp>

namespace tessera::launch {

namespace {

long to_long(const std::string& s, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || errno != 0 || end != s.c_str() + s.size())
    throw InputError("fork server: " + what + " '" + s + "' is not an integer");
  return v;
}

}  // namespace

const char* fork_role_name(ForkRole role) {
  return role == ForkRole::kCoordinator ? "coordinator" : "agent";
}

void ForkSpec::validate() const {
  if (pid_fd < 0) throw InputError("fork server: pid_fd must be >= 0");
  if (children.empty()) throw InputError("fork server: children must not be empty");
  for (std::size_t k = 0; k < children.size(); ++k) {
    const ForkChild& c = children[k];
    const std::string at = "fork server: child " + std::to_string(k) + ": ";
    if (c.argv.empty()) throw InputError(at + "argv must not be empty");
    if (c.log.empty()) throw InputError(at + "log must not be empty");
    if (c.stdout_fd < -1) throw InputError(at + "stdout_fd must be -1 or a descriptor");
  }
}

std::vector<std::string> encode_fork_spec(const ForkSpec& spec) {
  spec.validate();
  std::vector<std::string> out = {"--pid-fd", std::to_string(spec.pid_fd)};
  if (spec.agents_batch) out.push_back("--agents-batch");
  for (const ForkChild& c : spec.children) {
    out.insert(out.end(), {"--child", fork_role_name(c.role), c.log, std::to_string(c.stdout_fd),
                           std::to_string(c.argv.size())});
    out.insert(out.end(), c.argv.begin(), c.argv.end());
  }
  return out;
}

ForkSpec decode_fork_spec(const std::vector<std::string>& args) {
  ForkSpec spec;
  std::size_t i = 0;
  auto next = [&](const std::string& what) -> const std::string& {
    if (i >= args.size()) throw InputError("fork server: missing " + what);
    return args[i++];
  };
  if (next("--pid-fd") != "--pid-fd") throw InputError("fork server: expected --pid-fd first");
  spec.pid_fd = static_cast<int>(to_long(next("the pid descriptor"), "--pid-fd"));
  if (i < args.size() && args[i] == "--agents-batch") {
    ++i;
    spec.agents_batch = true;
  }
  while (i < args.size()) {
    const std::string& tag = next("--child");
    if (tag != "--child") throw InputError("fork server: expected --child, got '" + tag + "'");
    ForkChild c;
    const std::string& role = next("a role");
    if (role == "coordinator")
      c.role = ForkRole::kCoordinator;
    else if (role == "agent")
      c.role = ForkRole::kAgent;
    else
      throw InputError("fork server: role '" + role + "' is not coordinator or agent");
    c.log = next("a log file");
    c.stdout_fd = static_cast<int>(to_long(next("a stdout descriptor"), "stdout descriptor"));
    const long argc = to_long(next("an argument count"), "argument count");
    if (argc < 1 || static_cast<std::size_t>(argc) > args.size() - i)
      throw InputError("fork server: argument count " + std::to_string(argc) +
                       " does not fit the " + std::to_string(args.size() - i) + " arguments left");
    c.argv.assign(args.begin() + static_cast<long>(i), args.begin() + static_cast<long>(i) + argc);
    i += static_cast<std::size_t>(argc);
    spec.children.push_back(std::move(c));
  }
  spec.validate();
  return spec;
}

std::string serialize_fork_spec(const ForkSpec& spec) {
  std::string out;
  for (const std::string& item : encode_fork_spec(spec)) {
    if (item.find('\0') != std::string::npos)
      throw InputError("fork server: an argument contains a NUL byte");
    out += item;
    out += '\0';
  }
  return out;
}

ForkSpec parse_fork_spec(const std::string& text) {
  if (text.empty() || text.back() != '\0')
    throw InputError("fork server: the spec is empty or cut short (no final NUL)");
  std::vector<std::string> items;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = text.find('\0', at);
    items.push_back(text.substr(at, end - at));
    at = end + 1;
  }
  return decode_fork_spec(items);
}

std::size_t longest_command_line(const ForkSpec& spec) {
  std::size_t longest = 0;
  for (const ForkChild& c : spec.children) {
    std::size_t n = 0;
    for (const std::string& a : c.argv) n += a.size() + 1;
    longest = std::max(longest, n);
  }
  return longest;
}

void enter_child_process(const ForkChild& child) {
  // The coordinator gets a session of its own (and so its own process group, as the agents):
  // with the kernel's autogroup scheduling (sched_autogroup_enabled, Debian's default) a
  // session is one scheduling group, so the coordinator's single-threaded partition, which
  // runs while the agents start up, gets as much CPU as all the agents' start-up together
  // instead of a seventh of it (coordinator/file_partition.hpp). Without autogroup nothing
  // changes. setsid cannot fail in a fresh child (not yet a group leader); if it did,
  // setpgid still gives the own process group that launch signals.
  if (child.role != ForkRole::kCoordinator || setsid() < 0) setpgid(0, 0);
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
  const int fd = open(child.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd >= 0) {
    dup2(child.stdout_fd >= 0 ? child.stdout_fd : fd, 1);
    dup2(fd, 2);
    close(fd);
  }
}

}  // namespace tessera::launch
