// `tessera launch` through its fork server (launch/fork_server/: Fast DDS loaded once, the
// coordinator and the agents forked from it) and through the exec fallback
// (--no-fork-server): the same iterates as the in-process engine, forked processes that look
// like the executables they stand for and are launch's own children, a clean SIGINT, and the
// fork server's argv encoding; agents in SCHED_BATCH until their assignment (launch's
// default, launch/startup_batch.hpp).
// Domains used here: 50-53, 217-218 (each test its own, so ctest -j is safe).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>
#include <thread>
#include <vector>

#include "dds_process_support.hpp"
#include "launch/fork_spec.hpp"
#include "launch/launch_children.hpp"
#include "launch/startup_batch.hpp"
#include "transport/fastdds/shm_leftovers.hpp"

namespace tessera::test::dds {
namespace {

// The same solve in process (`tessera solve`) and with `tessera launch extra...` on `domain`:
// same rounds, cost equal to 1e-9 relative, and no shared-memory file left behind.
void expect_launch_gives_the_in_process_iterates(const std::string& extra, int domain,
                                                 const std::string& expected_mode) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 240 --robots 3 --seed 5");
  const std::string solver = " --agents 3 --algorithm irbcd --partition eco --seed 7 --init file";
  const std::string ip = solve_summary(dir, graph, solver, "ip");
  ASSERT_FALSE(::testing::Test::HasFailure());
  ASSERT_GT(json_field(ip, "rounds"), 1) << "the graph should need a few rounds";
  std::string out;

  const auto before = shm_files();
  const int rc = run_command(bin("tessera") + " launch " + graph + solver + " --no-certify" +
                                 " --domain " + std::to_string(domain) + " --timeout 60 --json " +
                                 dir + "/dds.json " + extra + " 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find(expected_mode), std::string::npos) << out;
  EXPECT_NE(out.find("summary:"), std::string::npos) << out;
  const std::string dds = slurp(dir + "/dds.json");
  // The coordinator partitioned launch's file while the agents started up.
  EXPECT_NE(dds.find("\"partition_early\": true"), std::string::npos) << dds;
  EXPECT_EQ(json_field(dds, "rounds"), json_field(ip, "rounds")) << dds << ip;
  const double cost = json_field(ip, "cost");
  EXPECT_NEAR(json_field(dds, "cost"), cost, 1e-9 * cost) << dds << ip;
  const auto leaked = leaked_shm_files(before, domain);
  EXPECT_TRUE(leaked.empty()) << join(leaked);
}

TEST(DdsForkServer, LaunchThroughTheForkServerGivesTheInProcessIterates) {
  expect_launch_gives_the_in_process_iterates("", 50, "forked by tessera-fork-server");
}

TEST(DdsForkServer, ExecFallbackGivesTheInProcessIterates) {
  expect_launch_gives_the_in_process_iterates("--no-fork-server", 51, "each exec'ed");
}

// The parent pid and command line of a process, from /proc.
long parent_of(long pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("PPid:", 0) == 0) return std::stol(line.substr(5));
  return -1;
}

// Field `index` (1-based, as in proc(5)) of /proc/<pid>/stat or of a task's stat file.
long stat_field(const std::string& path, int index) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return -1000;
  std::istringstream rest(text.substr(close + 2));  // field 3 onwards
  std::string field;
  for (int k = 3; rest >> field; ++k)
    if (k == index) return std::stol(field);
  return -1000;
}

// The pids of the processes whose command line matches `pattern` (pgrep -f).
std::vector<long> pids_of(const std::string& pattern) {
  std::string out;
  run_command("pgrep -f '" + pattern + "'", &out);
  std::vector<long> pids;
  std::istringstream in(out);
  for (long pid; in >> pid;) pids.push_back(pid);
  return pids;
}

// A 2-agent launch through the fork server on `domain` with enough rounds (3000 poses from
// their file poses) that it is still going when its processes are looked at after round 2;
// end() interrupts it and checks that everything stopped cleanly. Whatever an assertion leaves
// running is killed by the destructor.
struct LongForkedRun {
  std::string dir = temp_dir();
  std::string run_id;
  int domain;
  std::set<std::string> shm_before = shm_files();
  Process launch;

  LongForkedRun(const std::string& name, int domain_, const std::vector<std::string>& extra)
      : run_id(name + "-" + std::to_string(getpid())), domain(domain_) {
    std::vector<std::string> argv = {
        bin("tessera"), "launch", "--agents",     "2",
        "--poses",      "3000",   "--domain",     std::to_string(domain),
        "--run-id",     run_id,   "--init",       "file",
        "--grad-tol",   "1e-12",  "--max-rounds", "100000",
        "--partition",  "fast",   "--timeout",    "60"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    launch = start(argv, dir + "/launch.log");
  }
  ~LongForkedRun() { run_command("pkill -9 -f '[t]essera-.*--run-id " + run_id + "'", nullptr); }

  // SIGINT to launch: exit 130 naming the interruption, no process and no shared-memory file
  // of the run left.
  void end() {
    kill(launch.pid, SIGINT);
    ASSERT_TRUE(wait_all({&launch}, 15)) << launch.output();
    EXPECT_EQ(launch.exit_code, 130) << launch.output();
    EXPECT_NE(launch.output().find("interrupted"), std::string::npos) << launch.output();
    std::string ps;
    run_command("pgrep -fc '[t]essera-.*--run-id " + run_id + "'", &ps);
    EXPECT_EQ(std::stoi(ps), 0) << ps;
    const auto leaked = leaked_shm_files(shm_before, domain);
    EXPECT_TRUE(leaked.empty()) << join(leaked);
  }
};

// Launch's default: agents start in SCHED_BATCH (launch/startup_batch.hpp) and leave it with
// their assignment, so every thread of theirs runs the rounds as a normal thread.
TEST(DdsForkServer, BatchStartedAgentsRunTheirRoundsAsNormalThreads) {
  LongForkedRun run("batch", 217, {});
  const std::string& run_id = run.run_id;
  const Process& launch = run.launch;
  ASSERT_TRUE(wait_for_round(launch, 2, 30)) << launch.output();
  const std::vector<long> agents = pids_of("[t]essera-agent.*--run-id " + run_id + " ");
  ASSERT_EQ(agents.size(), 2u);
  for (long pid : agents) {
    run_command("ls /proc/" + std::to_string(pid) + "/task > " + run.dir + "/tasks", nullptr);
    std::ifstream tasks(run.dir + "/tasks");
    int seen = 0;
    for (std::string tid; tasks >> tid; ++seen)  // field 41: the scheduling policy
      EXPECT_EQ(stat_field("/proc/" + std::to_string(pid) + "/task/" + tid + "/stat", 41),
                SCHED_OTHER)
          << "agent " << pid << " thread " << tid;
    EXPECT_GT(seen, 1);
  }
  run.end();
}

// Runs `checks` in a forked child (scheduling settings are per process and per thread, so the
// test process stays untouched) and expects it to report no failed check (a bit per check).
void expect_checks_pass_in_child(int (*checks)()) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(checks());
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "failed checks (bits): " << WEXITSTATUS(status);
}

// In a forked child (so the test's threads keep their policy): enter_startup_batch puts the
// calling thread and every thread it creates in SCHED_BATCH; restore_startup_batch puts every
// thread back, once. Each failed check is one bit of the child's exit code.
int batch_and_restore_in_child() {
  int failed = 0;
  if (!launch::restore_startup_batch().empty()) failed |= 1 << 0;  // nothing entered yet
  if (!launch::enter_startup_batch()) failed |= 1 << 1;
  if (sched_getscheduler(0) != SCHED_BATCH) failed |= 1 << 2;
  std::atomic<int> sleeper_policy{-1};
  std::atomic<bool> restored{false};
  std::thread sleeper([&] {  // created batch, alive while restoring
    if (sched_getscheduler(0) != SCHED_BATCH) sleeper_policy = -2;
    while (!restored) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (sleeper_policy != -2) sleeper_policy = sched_getscheduler(0);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const std::string what = launch::restore_startup_batch();
  restored = true;
  sleeper.join();
  if (what.find("2 thread(s)") == std::string::npos) failed |= 1 << 3;
  if (sched_getscheduler(0) != SCHED_OTHER) failed |= 1 << 4;
  if (sleeper_policy != SCHED_OTHER) failed |= 1 << 5;
  if (!launch::restore_startup_batch().empty()) failed |= 1 << 6;  // idempotent
  return failed;
}

TEST(StartupBatch, NewThreadsInheritItAndRestoreBringsEveryThreadBack) {
  expect_checks_pass_in_child(batch_and_restore_in_child);
}

TEST(DdsForkServer, ForkedProcessesAreLaunchsChildrenNamedLikeTheExecutablesAndStopOnSigint) {
  LongForkedRun run("forked", 52, {});
  const std::string& run_id = run.run_id;
  const Process& launch = run.launch;
  ASSERT_TRUE(wait_for_round(launch, 2, 30)) << launch.output();
  EXPECT_NE(launch.output().find("forked by tessera-fork-server"), std::string::npos);
  // pgrep -f reads the command line each forked child shows: its executable's argv.
  for (const std::string& pattern : {"[t]essera-coordinator --agents 2 .*--run-id " + run_id + " ",
                                     "[t]essera-agent.*--id 0 --run-id " + run_id + " ",
                                     "[t]essera-agent.*--id 1 --run-id " + run_id + " "}) {
    std::string pids;
    run_command("pgrep -f '" + pattern + "'", &pids);
    ASSERT_FALSE(pids.empty()) << pattern;
    const long pid = std::stol(pids);
    EXPECT_EQ(pids.find('\n'), pids.size() - 1) << "one process for " << pattern << ": " << pids;
    EXPECT_EQ(parent_of(pid), launch.pid) << pattern;  // re-parented: launch waits for it
    std::ifstream comm("/proc/" + std::to_string(pid) + "/comm");
    std::string name;
    std::getline(comm, name);
    EXPECT_EQ(name.rfind("tessera-", 0), 0u) << name;
  }
  run.end();
}

TEST(DdsForkServer, BadFileStopsTheForkedRunWithTheAgentsReason) {
  const std::string dir = temp_dir();
  const std::string graph = write_file(dir, "bad.g2o", "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 7 1 0\n");
  std::string out;
  const int rc = run_command(
      bin("tessera") + " launch " + graph + " --agents 2 --domain 53 --timeout 30 2>&1", &out);
  EXPECT_EQ(rc, 2) << out;  // bad input: tessera solve's exit code (launch/failure_report.hpp)
  EXPECT_NE(out.find("forked by tessera-fork-server"), std::string::npos) << out;
  EXPECT_NE(out.find("bad.g2o"), std::string::npos) << out;  // the agent's message names the file
  EXPECT_NE(out.find("exit 2"), std::string::npos) << out;   // its exit code, as when exec'ed
}

// More agents than poses: every agent says so and exits with 2; launch shows the message once,
// under all their names, and exits with 2 as `tessera solve` does for bad input.
TEST(DdsForkServer, AGraphTooSmallForTheTeamIsReportedOnceWithTheInputErrorsExitCode) {
  const std::string dir = temp_dir();
  const std::string graph = write_file(
      dir, "two.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n");
  std::string out;
  const int rc = run_command(
      bin("tessera") + " launch " + graph + " --agents 3 --domain 53 --timeout 30 2>&1", &out);
  EXPECT_EQ(rc, 2) << out;
  EXPECT_NE(out.find("agents 0, 1 and 2 (exit 2):"), std::string::npos) << out;
  EXPECT_NE(out.find("cannot split 2 poses among 3 robots"), std::string::npos) << out;
  EXPECT_EQ(out.find("tessera-agent[1]"), std::string::npos) << out;  // shown once, as agent 0's
}

// A child that ignores SIGINT is SIGKILLed after the grace period, and launch names it (its
// shared-memory files cannot be removed by it: the message says where leftovers come from).
TEST(DdsForkServer, StopAllKillsAndNamesAChildThatIgnoresSigint) {
  // The child says when it ignores SIGINT: stop_all's SIGINT must not come before that (on a
  // loaded host the child may not have run yet, and then SIGINT ends it with 130).
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    signal(SIGINT, SIG_IGN);
    if (write(ready[1], "r", 1) != 1) _exit(1);
    for (;;) pause();
  }
  close(ready[1]);
  char byte = 0;
  ASSERT_EQ(read(ready[0], &byte, 1), 1);
  close(ready[0]);
  std::vector<launch::Child> children(1);
  children[0].name = "agent 7";
  children[0].pid = pid;
  children[0].running = true;
  testing::internal::CaptureStderr();
  launch::stop_all(children, 0.3);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(children[0].running);
  EXPECT_EQ(children[0].code, 128 + SIGKILL);
  EXPECT_NE(err.find("agent 7 did not stop within"), std::string::npos) << err;
  EXPECT_NE(err.find("SIGKILL"), std::string::npos) << err;
}

// After a run that lost a process, launch removes the shared-memory files its dead processes
// left (transport/fastdds/shm_leftovers.hpp): ports of its domain and segments its processes
// mapped, each only when no live process holds its lock. Here in a directory of its own, with locks
// held by this test (flock locks of two open() calls conflict, even in one process).
TEST(DdsShmLeftovers, OnlyDeadPortsOfTheDomainAndDeadSegmentsOfTheRunAreRemoved) {
  const std::string dir = temp_dir();
  auto touch = [&](const std::string& name) { std::ofstream(dir + "/" + name) << "x"; };
  auto exists = [&](const std::string& name) {
    return access((dir + "/" + name).c_str(), F_OK) == 0;
  };
  auto hold = [&](const std::string& name) {
    const int fd = open((dir + "/" + name).c_str(), O_RDWR);
    EXPECT_GE(fd, 0);
    EXPECT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
    return fd;
  };
  // Domain 3: ports 8150 ... 8399.
  const std::vector<std::string> dead_port = {"fastrtps_port8160", "fastrtps_port8160_el",
                                              "sem.fastrtps_port8160_mutex"};
  const std::vector<std::string> dead_shared_port = {"fastrtps_port8150", "fastrtps_port8150_sl"};
  const std::vector<std::string> live_port = {"fastrtps_port8161", "fastrtps_port8161_el",
                                              "sem.fastrtps_port8161_mutex"};
  const std::vector<std::string> other_domain = {"fastrtps_port8400", "fastrtps_port8400_el",
                                                 "fastrtps_port7411", "fastrtps_port7411_el"};
  const std::vector<std::string> lock_gone = {"fastrtps_port8170", "sem.fastrtps_port8170_mutex"};
  const std::vector<std::string> lock_gone_mapped = {"fastrtps_port8180"};
  const std::vector<std::string> dead_segment = {"fastrtps_0123456789abcdef",
                                                 "fastrtps_0123456789abcdef_el"};
  const std::vector<std::string> unlisted_segment = {"fastrtps_fedcba9876543210",
                                                     "fastrtps_fedcba9876543210_el"};
  const std::vector<std::string> live_segment = {"fastrtps_aaaaaaaaaaaaaaaa",
                                                 "fastrtps_aaaaaaaaaaaaaaaa_el"};
  for (const auto* group : {&dead_port, &dead_shared_port, &live_port, &other_domain, &lock_gone,
                            &lock_gone_mapped, &dead_segment, &unlisted_segment, &live_segment})
    for (const auto& f : *group) touch(f);
  const int mapped_fd = open((dir + "/fastrtps_port8180").c_str(), O_RDONLY);
  ASSERT_GE(mapped_fd, 0);
  void* mapped = mmap(nullptr, 1, PROT_READ, MAP_SHARED, mapped_fd, 0);
  ASSERT_NE(mapped, MAP_FAILED);
  const int port_lock = hold("fastrtps_port8161_el");
  const int segment_lock = hold("fastrtps_aaaaaaaaaaaaaaaa_el");

  transport::ShmCleanupOptions o;
  o.domain = 3;
  o.dir = dir;
  o.segments = {"fastrtps_0123456789abcdef", "fastrtps_aaaaaaaaaaaaaaaa"};
  const transport::ShmCleanupResult r = transport::remove_dead_shm_files(o);
  std::vector<std::string> expected = dead_port;
  expected.insert(expected.end(), dead_shared_port.begin(), dead_shared_port.end());
  expected.insert(expected.end(), lock_gone.begin(), lock_gone.end());
  expected.insert(expected.end(), dead_segment.begin(), dead_segment.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(r.removed, expected);
  EXPECT_EQ(r.in_use, 3u);  // the held port, the mapped port and the held segment
  for (const auto& f : expected) EXPECT_FALSE(exists(f)) << f;
  for (const auto* group :
       {&live_port, &other_domain, &lock_gone_mapped, &unlisted_segment, &live_segment})
    for (const auto& f : *group) EXPECT_TRUE(exists(f)) << f << " was removed";
  munmap(mapped, 1);
  close(mapped_fd);
  close(port_lock);
  close(segment_lock);

  // A live process's own segment is found through its maps (here: this test maps one).
  const std::string shm = dir + "/fastrtps_5a5a5a5a5a5a5a5a";
  { std::ofstream(shm) << std::string(4096, '\0'); }
  const int fd = open(shm.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  void* map = mmap(nullptr, 4096, PROT_READ, MAP_SHARED, fd, 0);
  ASSERT_NE(map, MAP_FAILED);
  EXPECT_EQ(transport::mapped_segments({getpid()}).count("fastrtps_5a5a5a5a5a5a5a5a"), 1u);
  munmap(map, 4096);
  close(fd);
  unlink(shm.c_str());
  EXPECT_EQ(transport::mapped_segments({getpid()}).count("fastrtps_5a5a5a5a5a5a5a5a"), 0u);
}

// Dead ports of the run's domain that an earlier run's processes left (an abort, a SIGKILLed agent
// started by hand) are removed before launch starts its processes: left there, they kept every
// later launch on that domain from discovering its peers. A run that ends normally
// removes nothing afterwards, so without the removal before the run the planted files stay.
TEST(DdsShmLeftovers, LaunchRemovesTheDomainsDeadPortsBeforeTheRun) {
  const int domain = 218;
  const std::string port = std::to_string(7400 + 250 * domain + 200);  // no participant's port
  const std::vector<std::string> planted = {"/dev/shm/fastrtps_port" + port,
                                            "/dev/shm/fastrtps_port" + port + "_el",
                                            "/dev/shm/sem.fastrtps_port" + port + "_mutex"};
  for (const auto& f : planted) std::ofstream(f) << "x";
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 120 --robots 2 --seed 3");
  std::string out;
  const int rc = run_command(bin("tessera") + " launch " + graph +
                                 " --agents 2 --no-certify --timeout 60 --domain " +
                                 std::to_string(domain) + " 2>&1",
                             &out);
  for (const auto& f : planted) {
    EXPECT_NE(access(f.c_str(), F_OK), 0) << f << " is still there\n" << out;
    unlink(f.c_str());
  }
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("removed 3 shared-memory files of dead processes of domain 218 from "
                     "/dev/shm before the run"),
            std::string::npos)
      << out;
}

TEST(DdsForkServer, ArgvEncodingRoundTripsAndRejectsMalformedInput) {
  launch::ForkSpec spec;
  spec.pid_fd = 7;
  spec.children.push_back({launch::ForkRole::kCoordinator, "/tmp/c.log", 4, {"/b/c", "--x", ""}});
  spec.children.push_back({launch::ForkRole::kAgent, "/tmp/a 0.log", -1, {"/b/a", "--child"}});
  const std::vector<std::string> args = launch::encode_fork_spec(spec);
  const launch::ForkSpec back = launch::decode_fork_spec(args);
  EXPECT_EQ(back.pid_fd, 7);
  EXPECT_FALSE(back.agents_batch);
  ASSERT_EQ(back.children.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(back.children[k].role, spec.children[k].role);
    EXPECT_EQ(back.children[k].log, spec.children[k].log);
    EXPECT_EQ(back.children[k].stdout_fd, spec.children[k].stdout_fd);
    EXPECT_EQ(back.children[k].argv, spec.children[k].argv);  // "--child" as an argument too
  }
  auto broken = [&](std::size_t at, const std::string& value) {
    std::vector<std::string> a = args;
    a[at] = value;
    return a;
  };
  EXPECT_THROW(launch::decode_fork_spec({}), InputError);
  EXPECT_THROW(launch::decode_fork_spec({"--pid-fd", "3"}), InputError);  // no child
  EXPECT_THROW(launch::decode_fork_spec(broken(1, "x")), InputError);
  EXPECT_THROW(launch::decode_fork_spec(broken(3, "worker")), InputError);
  EXPECT_THROW(launch::decode_fork_spec(broken(6, "99")), InputError);  // argc past the end
  EXPECT_THROW(launch::decode_fork_spec(broken(6, "0")), InputError);
  launch::ForkSpec batch = spec;  // launch's default
  batch.agents_batch = true;
  const launch::ForkSpec batch_back = launch::decode_fork_spec(launch::encode_fork_spec(batch));
  EXPECT_TRUE(batch_back.agents_batch);
  EXPECT_EQ(batch_back.children.size(), 2u);
  launch::ForkSpec no_log = spec;
  no_log.children[1].log.clear();
  EXPECT_THROW(launch::encode_fork_spec(no_log), InputError);
  // The bytes that go down the pipe.
  const std::string text = launch::serialize_fork_spec(spec);
  EXPECT_EQ(launch::parse_fork_spec(text).children[0].argv, spec.children[0].argv);
  EXPECT_THROW(launch::parse_fork_spec(text.substr(0, text.size() - 1)), InputError);  // cut short
  EXPECT_THROW(launch::parse_fork_spec(""), InputError);
  EXPECT_EQ(launch::longest_command_line(spec), std::string("/b/a --child ").size());  // the agent
  // The executable says what is wrong and exits 2 (as the other executables on bad options).
  std::string out;
  EXPECT_EQ(run_command(bin("tessera-fork-server") + " --pid-fd 1 --child worker 2>&1", &out), 2)
      << out;
  EXPECT_NE(out.find("tessera-fork-server: error: usage"), std::string::npos) << out;
  EXPECT_EQ(run_command("printf 'bad' | " + bin("tessera-fork-server") +
                            " --spec-fd 0 --title-room '    ' 2>&1",
                        &out),
            2)
      << out;
  EXPECT_NE(out.find("cut short"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::test::dds
