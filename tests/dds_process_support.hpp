#pragma once
// Helpers for the DDS runtime tests (header-only; not a *_test.cpp so it is no test of its
// own): the command lines of tessera-agent (batch and --online) / tessera-coordinator, start
// them in the background, wait for them or for a line of their output with a deadline (a test
// never hangs: stragglers are SIGKILLed), write the small graphs the tests use, run a solve or
// an online launch and read its summary, read what the agents dumped, and find shared-memory
// files nobody uses any more.

#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_support.hpp"

namespace tessera::test::dds {

using Clock = std::chrono::steady_clock;

/// A background process whose stdout+stderr go to a file.
struct Process {
  pid_t pid = -1;
  std::string log;
  int exit_code = -1;       ///< After wait: exit status, or 128 + signal.
  double exit_after_s = 0;  ///< Seconds from start() to exit, as seen by wait_all.
  Clock::time_point started;
  bool done = false;

  std::string output() const {
    std::ifstream f(log);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  }
};

inline Process start(const std::vector<std::string>& argv, const std::string& log) {
  Process p;
  p.log = log;
  p.started = Clock::now();
  p.pid = fork();
  if (p.pid == 0) {
    int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    // A fresh process group so a signal sent to the test runner's group does not reach it twice.
    setpgid(0, 0);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return p;
}

/// Waits for every process up to `timeout_s` (polling every 10 ms: test code only), then
/// SIGKILLs the rest and returns false.
inline bool wait_all(std::vector<Process*> procs, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    bool all = true;
    for (Process* p : procs) {
      if (p->done) continue;
      int status = 0;
      pid_t r = waitpid(p->pid, &status, WNOHANG);
      if (r == p->pid) {
        p->done = true;
        p->exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        p->exit_after_s = std::chrono::duration<double>(Clock::now() - p->started).count();
      } else {
        all = false;
      }
    }
    if (all) return true;
    if (Clock::now() > deadline) {
      for (Process* p : procs)
        if (!p->done) {
          kill(p->pid, SIGKILL);
          waitpid(p->pid, nullptr, 0);
          p->done = true;
          p->exit_code = -2;  // hung
        }
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

/// `argv` run through /usr/bin/env with `assignment` ("NAME=value") in its environment (the
/// agents' test-only hooks, agent/test_abort_hook.hpp).
inline std::vector<std::string> with_env(const std::string& assignment,
                                         std::vector<std::string> argv) {
  argv.insert(argv.begin(), {"/usr/bin/env", assignment});
  return argv;
}

/// tessera-agent for robot `id` of `robots` on `graph`, run `run` on `domain`, then `extra`.
inline std::vector<std::string> agent_args(const std::string& graph, int robots, int id,
                                           const std::string& run, int domain,
                                           const std::vector<std::string>& extra = {}) {
  std::vector<std::string> a = {
      bin("tessera-agent"), "--graph",  graph, "--robots", std::to_string(robots), "--id",
      std::to_string(id),   "--run-id", run,   "--domain", std::to_string(domain)};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

/// tessera-coordinator for `agents` agents, run `run` on `domain`, then `extra`.
inline std::vector<std::string> coordinator_args(int agents, const std::string& run, int domain,
                                                 const std::vector<std::string>& extra = {}) {
  std::vector<std::string> a = {
      bin("tessera-coordinator"), "--agents", std::to_string(agents), "--run-id", run, "--domain",
      std::to_string(domain)};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

/// Starts agents 0..agents-1 (`reverse`: highest id first), each with `extra` and
/// `--dump-local DIR/local<k>.txt` when `dump_local`, logging to DIR/agent<k>.log.
inline std::vector<Process> start_agents(const std::string& dir, const std::string& graph,
                                         int agents, const std::string& run, int domain,
                                         const std::vector<std::string>& extra, bool dump_local,
                                         bool reverse = false) {
  std::vector<Process> procs;
  procs.reserve(static_cast<std::size_t>(agents) + 1);  // room for a coordinator after them
  for (int i = 0; i < agents; ++i) {
    const int k = reverse ? agents - 1 - i : i;
    std::vector<std::string> a = agent_args(graph, agents, k, run, domain, extra);
    if (dump_local)
      a.insert(a.end(), {"--dump-local", dir + "/local" + std::to_string(k) + ".txt"});
    procs.push_back(start(a, dir + "/agent" + std::to_string(k) + ".log"));
  }
  return procs;
}

/// Pointers to `first` and every process of `rest` (for wait_all).
inline std::vector<Process*> all_of(Process& first, std::vector<Process>& rest) {
  std::vector<Process*> all = {&first};
  for (auto& p : rest) all.push_back(&p);
  return all;
}

/// One run on `domain` in `dir`: a coordinator with `coordinator_extra` and `agents` agents on
/// `graph` (--timeout 20, --dump-local DIR/local<k>.txt). `agents_first`: the agents start
/// first, highest id first (the coordinator then finds announcements already published).
/// Every process must end within `wait_s` with exit code 0 (test failures otherwise).
inline void run_to_the_end(const std::string& dir, const std::string& graph, int agents,
                           const std::string& run, int domain,
                           const std::vector<std::string>& coordinator_extra, double wait_s,
                           bool agents_first = false) {
  const auto coordinator = [&] {
    return start(coordinator_args(agents, run, domain, coordinator_extra),
                 dir + "/coordinator.log");
  };
  Process coord;
  if (!agents_first) coord = coordinator();
  std::vector<Process> procs =
      start_agents(dir, graph, agents, run, domain, {"--timeout", "20"}, true, agents_first);
  if (agents_first) coord = coordinator();
  std::vector<Process*> all = all_of(coord, procs);
  EXPECT_TRUE(wait_all(all, wait_s)) << "a process hung";
  for (Process* p : all) EXPECT_EQ(p->exit_code, 0) << p->output();
}

/// The pid of agent `id` of run `run_id` (a tessera-agent process, started by launch or by
/// hand), 0 when there is none.
inline pid_t agent_pid(const std::string& run_id, int id) {
  std::string pid;
  // "[t]" keeps the pattern from matching the shell that runs pgrep.
  run_command("pgrep -f '[t]essera-agent.*--id " + std::to_string(id) + " --run-id " + run_id +
                  " ' | head -1",
              &pid);
  return pid.empty() ? 0 : static_cast<pid_t>(std::stol(pid));
}

/// Waits until `text` appears in `p`'s output (polling every 20 ms); false after `timeout_s`.
inline bool wait_for_output(const Process& p, const std::string& text, double timeout_s) {
  const auto until = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < until) {
    if (p.output().find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// The highest K of the progress lines ("round K: ..." and "round K (restart): ...") in
/// `text`, or -1 when there is none.
inline long last_progress_round(const std::string& text) {
  static const std::regex line(R"((^|\n)round (\d+)( \(restart\))?:)");
  long last = -1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator();
       ++it)
    last = std::max(last, std::stol((*it)[2].str()));
  return last;
}

/// Waits until `p` printed a progress line of round `round` or later (the coordinator prints
/// at most ~10 a second, so a given round may have no line); false after `timeout_s`.
inline bool wait_for_round(const Process& p, long round, double timeout_s) {
  const auto until = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < until) {
    if (last_progress_round(p.output()) >= round) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// `tessera generate <args> --out <path>`; a failure is a test failure (with the output).
inline std::string generate_graph(const std::string& path, const std::string& args) {
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " generate " + args + " --out " + path, &out), 0) << out;
  return path;
}

/// An 2D graph of `side` x `side` poses on a grid, joined by grid-neighbour odometry-like
/// measurements (noise free), with ids shuffled (fixed seed) so that contiguous id ranges
/// are a poor partition and the multilevel partitioner moves poses between agents.
/// Returns the g2o text; `poses` receives (x, y, theta) per id.
inline std::string grid_graph_g2o(int side, unsigned seed,
                                  std::vector<std::array<double, 3>>* poses_out = nullptr) {
  const int n = side * side;
  std::vector<int> id(n);
  for (int k = 0; k < n; ++k) id[k] = k;
  std::mt19937 rng(seed);
  std::shuffle(id.begin(), id.end(), rng);
  std::vector<std::array<double, 3>> pose(n);
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) pose[id[r * side + c]] = {1.0 * c, 1.0 * r, 0.05 * (r + c)};
  std::string out;
  char buf[256];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buf, sizeof(buf), "VERTEX_SE2 %d %.17g %.17g %.17g\n", k, pose[k][0], pose[k][1],
                  pose[k][2]);
    out += buf;
  }
  auto edge = [&](int a, int b) {
    const auto& pa = pose[a];
    const auto& pb = pose[b];
    const double dx = pb[0] - pa[0], dy = pb[1] - pa[1];
    const double c = std::cos(pa[2]), s = std::sin(pa[2]);
    std::snprintf(buf, sizeof(buf), "EDGE_SE2 %d %d %.17g %.17g %.17g 100 0 0 100 0 400\n", a, b,
                  c * dx + s * dy, -s * dx + c * dy, pb[2] - pa[2]);
    out += buf;
  };
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      if (c + 1 < side) edge(id[r * side + c], id[r * side + c + 1]);
      if (r + 1 < side) edge(id[r * side + c], id[(r + 1) * side + c]);
    }
  if (poses_out) *poses_out = pose;
  return out;
}

/// Shared-memory files of Fast DDS in /dev/shm.
inline std::set<std::string> shm_files() {
  std::set<std::string> out;
  if (DIR* d = opendir("/dev/shm")) {
    while (dirent* e = readdir(d)) {
      std::string name = e->d_name;
      if (name.find("fastrtps") != std::string::npos) out.insert(name);
    }
    closedir(d);
  }
  return out;
}

/// Files of /dev/shm mapped by some live process (from /proc/*/maps).
inline std::set<std::string> shm_files_in_use() {
  std::set<std::string> out;
  if (DIR* d = opendir("/proc")) {
    while (dirent* e = readdir(d)) {
      if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
      std::ifstream maps(std::string("/proc/") + e->d_name + "/maps");
      std::string line;
      while (std::getline(maps, line)) {
        auto pos = line.find("/dev/shm/");
        if (pos != std::string::npos) out.insert(line.substr(pos + 9));
      }
    }
    closedir(d);
  }
  return out;
}

/// The port number in a Fast DDS shared-memory file name ("fastrtps_port7411_el",
/// "sem.fastrtps_port7411_mutex"), or -1 for a segment file ("fastrtps_<hex>").
inline long shm_port(const std::string& name) {
  auto pos = name.find("fastrtps_port");
  if (pos == std::string::npos) return -1;
  return std::strtol(name.c_str() + pos + 13, nullptr, 10);
}

/// Fast DDS files that appeared since `before`, that no live process uses, and that belong
/// to `domain` (port files; ports 7400 + 250 domain ...) or to nobody (segment files): what
/// a run on that domain leaked. Tests on other domains may run at the same time, and their
/// files can be briefly unmapped, so a candidate counts only if it is still unused after
/// a short grace period.
inline std::set<std::string> leaked_shm_files(const std::set<std::string>& before, int domain) {
  auto candidates = [&] {
    std::set<std::string> in_use = shm_files_in_use();
    std::set<std::string> out;
    const long lo = 7400 + 250L * domain, hi = lo + 250;
    const std::set<std::string> now = shm_files();
    // Segment files cannot be told apart by domain: judge them only when no other domain
    // has been active meanwhile (a killed process elsewhere leaks segments by nature).
    bool others_active = false;
    for (const auto& f : now) {
      const long port = shm_port(f);
      if (!before.count(f) && port >= 0 && (port < lo || port >= hi)) others_active = true;
    }
    for (const auto& f : now) {
      if (before.count(f) || in_use.count(f)) continue;
      const long port = shm_port(f);
      if (port >= 0 && (port < lo || port >= hi)) continue;  // another domain's
      if (port < 0 && others_active) continue;
      // A deleted participant's segment kept readable on purpose, with its marker
      // (transport/fastdds/shm_segment_keeper.hpp): it goes 10 s later or at launch's end.
      if (port < 0 && f.compare(0, 9, "fastrtps_") == 0 &&
          std::ifstream("/dev/shm/tessera_kept_" + f.substr(9)).good())
        continue;
      // Lock files ("_el") are held with flock, not mapped: they belong to a port in use.
      if (f.size() > 3 && f.compare(f.size() - 3, 3, "_el") == 0 &&
          in_use.count(f.substr(0, f.size() - 3)))
        continue;
      out.insert(f);
    }
    return out;
  };
  std::set<std::string> first = candidates();
  if (first.empty()) return first;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::set<std::string> second = candidates(), out;
  for (const auto& f : first)
    if (second.count(f)) out.insert(f);
  return out;
}

/// Removes leaked files (after a SIGKILL test, which leaks by nature).
inline void remove_shm_files(const std::set<std::string>& files) {
  for (const auto& f : files) unlink(("/dev/shm/" + f).c_str());
}

inline std::string join(const std::set<std::string>& s) {
  std::string out;
  for (const auto& x : s) out += (out.empty() ? "" : ", ") + x;
  return out;
}

/// After a launch in which a process died inside Fast DDS (SIGKILL, an abort): launch's output
/// `out` says it removed the dead shared-memory files of `domain`
/// (transport/fastdds/shm_leftovers.hpp) and none of them is left since `before` (whatever is, is
/// removed here after the check).
inline void expect_launch_removed_dead_shm_files(const std::string& out,
                                                 const std::set<std::string>& before, int domain) {
  EXPECT_NE(out.find("shared-memory files of dead processes of domain " + std::to_string(domain)),
            std::string::npos)
      << out;
  const auto leaked = leaked_shm_files(before, domain);
  EXPECT_TRUE(leaked.empty()) << "left in /dev/shm: " << join(leaked);
  remove_shm_files(leaked);
}

/// The whole text of a file ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// A number field of a flat JSON summary; NaN when absent.
inline double json_field(const std::string& json, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + name + "\": ([-+0-9.eE]+)"))) return NAN;
  return std::stod(m[1]);
}

/// A field of a summary written by cli::JsonObject (`"key": value`) as text, the first at or
/// after offset `from`; "" when absent.
inline std::string json_text(const std::string& json, const std::string& key,
                             std::size_t from = 0) {
  const std::string tag = "\"" + key + "\": ";
  const std::size_t at = json.find(tag, from);
  if (at == std::string::npos) return "";
  const std::size_t begin = at + tag.size();
  return json.substr(begin, json.find_first_of(",\n}", begin) - begin);
}

/// That field's number; NaN when null or absent (absent also fails the test).
inline double json_number(const std::string& json, const std::string& key, std::size_t from = 0) {
  const std::string text = json_text(json, key, from);
  EXPECT_FALSE(text.empty()) << "no " << key;
  return text.empty() || text == "null" ? NAN : std::stod(text);
}

/// `tessera solve GRAPH ARGS --json DIR/NAME.json` (exit code 0, a test failure otherwise):
/// the summary's text.
inline std::string solve_summary(const std::string& dir, const std::string& graph,
                                 const std::string& args, const std::string& name) {
  const std::string json = dir + "/" + name + ".json";
  std::string out;
  EXPECT_EQ(
      run_command(bin("tessera") + " solve " + graph + " " + args + " --json " + json + " 2>&1",
                  &out),
      0)
      << out;
  return read_text_file(json);
}

/// `tessera launch GRAPH --agents 3 --online --domain D --timeout 60 ARGS --json
/// DIR/online.json --keep-logs DIR/logs`, killed after 240 s (exit code 0, a test failure
/// otherwise): the lead's summary. Each agent's is online_agent_summary(dir, a).
inline std::string online_launch(const std::string& dir, const std::string& graph, int domain,
                                 const std::string& args) {
  std::string out;
  EXPECT_EQ(
      run_command("timeout -s KILL 240 " + bin("tessera") + " launch " + graph +
                      " --agents 3 --online --domain " + std::to_string(domain) + " --timeout 60 " +
                      args + " --json " + dir + "/online.json" + " --keep-logs " + dir + "/logs",
                  &out),
      0)
      << out;
  return read_text_file(dir + "/online.json");
}

/// Agent `a`'s summary of an online_launch in `dir`.
inline std::string online_agent_summary(const std::string& dir, int a) {
  return read_text_file(dir + "/logs/agent-" + std::to_string(a) + ".json");
}

/// `tessera-agent --online` as agent `id` of `robots` of run `run` on `domain`, then `extra`.
inline std::vector<std::string> online_agent_args(int robots, int id, const std::string& run,
                                                  int domain,
                                                  const std::vector<std::string>& extra = {}) {
  std::vector<std::string> a = {bin("tessera-agent"),
                                "--online",
                                "--robots",
                                std::to_string(robots),
                                "--id",
                                std::to_string(id),
                                "--run-id",
                                run,
                                "--domain",
                                std::to_string(domain)};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

/// Agent 1 of run `run` on `domain`, started beside a lead (agent 0) that has `lead_extra`
/// on top of the same options (and agent 1 `other_extra`), must stop because its team options
/// differ from the lead's: exit code 2, within 60 s (a test failure otherwise). Its process,
/// for its output.
inline Process refused_beside_lead(const std::string& dir, const std::string& run, int domain,
                                   const std::vector<std::string>& lead_extra,
                                   const std::vector<std::string>& other_extra = {}) {
  std::vector<std::string> lead_args = {"--timeout", "60"};
  lead_args.insert(lead_args.end(), lead_extra.begin(), lead_extra.end());
  std::vector<std::string> other_args = {"--timeout", "60"};
  other_args.insert(other_args.end(), other_extra.begin(), other_extra.end());
  Process lead = start(online_agent_args(2, 0, run, domain, lead_args), dir + "/lead.log");
  Process other = start(online_agent_args(2, 1, run, domain, other_args), dir + "/other.log");
  const bool ended = wait_all({&other}, 60);
  kill(lead.pid, SIGTERM);
  wait_all({&lead}, 30);
  EXPECT_TRUE(ended) << "the agent with other options than the lead's did not stop";
  EXPECT_EQ(other.exit_code, 2) << other.output();
  return other;
}

/// Owned pose ids listed in an agent's --dump-local file.
inline std::vector<int> owned_of(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::vector<int> out;
  while (std::getline(f, line))
    if (line.rfind("OWNED ", 0) == 0) out.push_back(std::stoi(line.substr(6)));
  return out;
}

/// Pose ids of the VERTEX lines of a g2o file (a merged estimate holds VERTEX lines only).
inline std::set<long> vertex_ids(const std::string& path) {
  std::set<long> ids;
  std::ifstream f(path);
  for (std::string line; std::getline(f, line);)
    if (line.rfind("VERTEX", 0) == 0) ids.insert(std::stol(line.substr(line.find(' ') + 1)));
  return ids;
}

/// The partition the coordinator chose: the agent of every pose (by id, ascending), read from
/// the agents' --dump-local files DIR/local<k>.txt.
inline std::vector<int> assignment_of(const std::string& dir, int agents) {
  std::map<int, int> owner;
  for (int k = 0; k < agents; ++k)
    for (int id : owned_of(dir + "/local" + std::to_string(k) + ".txt")) owner[id] = k;
  std::vector<int> out;
  for (auto& [id, k] : owner) out.push_back(k);
  return out;
}

/// What a run of run_to_the_end wrote: the coordinator's summary and the partition it chose.
struct FinishedRun {
  std::string summary;          ///< DIR/summary.json (the coordinator's --summary).
  std::vector<int> assignment;  ///< The agent of every pose (assignment_of).
};

/// run_to_the_end with `--summary DIR/summary.json` after `coordinator_extra`, then what the
/// run wrote.
inline FinishedRun run_and_read(const std::string& dir, const std::string& graph, int agents,
                                const std::string& run, int domain,
                                std::vector<std::string> coordinator_extra, double wait_s) {
  coordinator_extra.insert(coordinator_extra.end(), {"--summary", dir + "/summary.json"});
  run_to_the_end(dir, graph, agents, run, domain, coordinator_extra, wait_s);
  return {read_text_file(dir + "/summary.json"), assignment_of(dir, agents)};
}

}  // namespace tessera::test::dds
