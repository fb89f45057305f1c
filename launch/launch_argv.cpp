#include "launch/launch_argv.hpp"

#include "io/number_text.hpp"
#include "launch/forwarded_flags.hpp"

namespace tessera::launch {

namespace {

// Appends the forwarded flags meant for `who` (in the table's order).
void append_forwarded(const LaunchOptions& o, ForwardTo who, std::vector<std::string>& argv) {
  for (const ForwardedFlag& f : forwarded_flags()) {
    if (f.to != who && f.to != ForwardTo::kBoth) continue;
    for (const auto& [name, value] : o.forwarded) {
      if (name != f.name) continue;
      argv.push_back(std::string("--") + f.target);
      if (f.valued) argv.push_back(value);
    }
  }
}

}  // namespace

std::vector<std::string> coordinator_argv(const LaunchOptions& o, const RunPaths& paths) {
  std::vector<std::string> a = {paths.bin + "/tessera-coordinator",
                                "--agents",
                                std::to_string(o.agents),
                                "--partition",
                                o.partition,
                                "--algorithm",
                                o.algorithm,
                                "--init",
                                o.init,
                                "--grad-tol",
                                exact_text(o.grad_tol),
                                "--max-rounds",
                                std::to_string(o.max_rounds),
                                "--rank",
                                std::to_string(o.rank),
                                "--seed",
                                std::to_string(o.seed),
                                "--partition-seed",  // `tessera solve` partitions with --seed
                                std::to_string(o.seed),
                                "--summary",
                                paths.summary,
                                "--graph-name",
                                paths.graph.substr(paths.graph.find_last_of('/') + 1),
                                "--run-timeout",
                                std::to_string(o.timeout_s),
                                "--progress"};
  if (o.certify) a.push_back("--certify");
  if (o.init_given) a.push_back("--gnc-solver-start");
  // The coordinator relays by default (docs/dds-runtime.md).
  if (!o.status_relay) a.push_back("--no-status-relay");
  // Every process runs here and the coordinator can read the whole file: it partitions the
  // file's structure while the agents start up (coordinator/file_partition.hpp). Robot files
  // are each robot's own: there the announcements are the only whole structure.
  if (o.robot_files().empty()) a.insert(a.end(), {"--graph", paths.graph});
  const std::vector<std::string> common = cli::session_argv(o.net.session);
  a.insert(a.end(), common.begin(), common.end());
  for (const auto& x : coordinator_loss_argv(o.loss)) a.push_back(x);
  append_forwarded(o, ForwardTo::kCoordinator, a);
  return a;
}

std::vector<std::string> agent_argv(const LaunchOptions& o, const RunPaths& paths, long k) {
  const std::vector<std::string> files = o.robot_files();
  std::vector<std::string> a = {paths.bin + "/tessera-agent",
                                "--graph",
                                files.empty() ? paths.graph : files[static_cast<std::size_t>(k)],
                                "--robots",
                                std::to_string(o.agents),
                                "--id",
                                std::to_string(k)};
  // Agent 0 solves the chordal start from the fork server's parsed file while the processes
  // discover each other (runtime/early_chordal.hpp).
  if (k == 0 && files.empty() && o.fork_server && o.init == "chordal")
    a.push_back("--early-chordal");
  const std::vector<std::string> common = cli::session_argv(o.net.session);
  a.insert(a.end(), common.begin(), common.end());
  for (const auto& x : agent_loss_argv(o.loss)) a.push_back(x);
  append_forwarded(o, ForwardTo::kAgents, a);
  return a;
}

ProcessPlan plan_processes(const LaunchOptions& o, const RunPaths& paths, int progress_fd) {
  ProcessPlan plan;
  plan.spec.agents_batch = o.agents_batch;  // launch/startup_batch.hpp
  plan.names.push_back("coordinator");
  plan.agent_ids.push_back(-1);
  plan.spec.children.push_back({ForkRole::kCoordinator, paths.work + "/coordinator.log",
                                progress_fd, coordinator_argv(o, paths)});
  for (long k = 0; k < o.agents; ++k) {
    plan.spec.children.push_back({ForkRole::kAgent,
                                  paths.work + "/agent" + std::to_string(k) + ".log", -1,
                                  agent_argv(o, paths, k)});
    plan.names.push_back("agent " + std::to_string(k));
    plan.agent_ids.push_back(k);
  }
  return plan;
}

}  // namespace tessera::launch
