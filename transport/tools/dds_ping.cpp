// tessera-dds-ping: measures the DDS transport as the runtime uses it. Two processes, one
// with --role echo and one with --role ping, on the same --domain / --run-id:
//  - discovery: time from creating the participant to passing the readiness barrier
//    (mutual discovery and every endpoint matched);
//  - round trip: ping sends a pose block (kind P) of --poses poses of rank --rank in
//    dimension --dim to echo, which sends it straight back; --count round trips.
// Prints one line of key=value results (times in ms). Used by scripts/bench/dds_transport.sh.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "arguments.hpp"
#include "transport/agent_session.hpp"
#include "transport/signal_watcher.hpp"

using namespace tessera;
using namespace tessera::transport;

int main(int argc, char** argv) {
  SignalWatcher signals;
  std::vector<std::string> argv_list(argv + 1, argv + argc);
  std::string role;
  long poses = 1000, rank = 5, dim = 3, count = 100, domain = 200;
  std::string run = "ping";
  double timeout = 20;
  try {
    cli::Arguments args(argv_list,
                        {"role", "poses", "rank", "dim", "count", "domain", "run-id", "timeout"},
                        {"help"});
    if (args.has("help")) {
      std::cout << "usage: tessera-dds-ping --role ping|echo [--poses 1000] [--rank 5] [--dim 3] "
                   "[--count 100]\n"
                   "                        [--domain 200] [--run-id ping] [--timeout 20]\n";
      return 0;
    }
    role = args.get_or("role", "");
    if (role != "ping" && role != "echo") throw InputError("option --role: must be ping or echo");
    poses = args.get_long("poses", poses);
    rank = args.get_long("rank", rank);
    dim = args.get_long("dim", dim);
    count = args.get_long("count", count);
    domain = args.get_long("domain", domain);
    run = args.get_or("run-id", run);
    timeout = args.get_double("timeout", timeout);
    if (poses < 1 || rank < 1 || (dim != 2 && dim != 3) || count < 1)
      throw InputError("--poses, --rank, --count must be positive and --dim 2 or 3");
  } catch (const InputError& e) {
    std::cerr << "tessera-dds-ping: error: " << e.what() << "\n";
    return 2;
  }
  const bool pinger = role == "ping";
  const auto t0 = std::chrono::steady_clock::now();
  SessionOptions so;
  so.run_id = run;
  so.domain = static_cast<int>(domain);
  so.agent_id = pinger ? 0 : 1;
  so.num_agents = 2;
  so.expect_coordinator = false;
  AgentSession s(so);
  signals.start(
      [&s](int signo) { s.mailroom().request_stop(exit_code_for_signal(signo), "interrupted"); });
  auto ms_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  };
  int code = 0;
  std::string missing;
  if (s.ready_barrier(Seconds(timeout), &missing) != WaitStatus::kReady) {
    std::cerr << "tessera-dds-ping: not ready: " << missing << "\n";
    code = 1;
  } else {
    const double discovery_ms = ms_since(t0);
    const std::uint32_t other = pinger ? 1 : 0;
    PoseBlockMessage block;
    block.sender = so.agent_id;
    block.kind = BlockKind::kP;
    block.rank = static_cast<std::uint32_t>(rank);
    block.dim = static_cast<std::uint32_t>(dim);
    for (long k = 0; k < poses; ++k) block.pose_ids.push_back(static_cast<std::uint32_t>(k));
    block.data.assign(static_cast<std::size_t>(poses * rank * (dim + 1)), 0.5);
    std::vector<double> rtt;
    for (long k = 0; k < count && code == 0; ++k) {
      ProtocolMessage in;
      if (pinger) {
        block.round = static_cast<std::uint32_t>(k);
        const auto t = std::chrono::steady_clock::now();
        s.send(OutgoingMessage{block, false, {other}});
        if (s.protocol().take(Seconds(timeout), &in) != WaitStatus::kReady) code = 1;
        rtt.push_back(ms_since(t));
      } else {
        if (s.protocol().take(Seconds(timeout), &in) != WaitStatus::kReady) {
          code = 1;
          break;
        }
        PoseBlockMessage back = std::get<PoseBlockMessage>(in);
        back.sender = so.agent_id;
        s.send(OutgoingMessage{back, false, {other}});
      }
    }
    if (pinger && code == 0) {
      std::sort(rtt.begin(), rtt.end());
      auto q = [&](double f) {
        return rtt[std::min(rtt.size() - 1, static_cast<std::size_t>(f * rtt.size()))];
      };
      std::printf(
          "discovery_ms=%.1f poses=%ld rank=%ld dim=%ld bytes=%zu count=%ld rtt_p50_ms=%.3f "
          "rtt_p90_ms=%.3f "
          "rtt_max_ms=%.3f\n",
          discovery_ms, poses, rank, dim, block.data.size() * 8 + block.pose_ids.size() * 4, count,
          q(0.5), q(0.9), rtt.back());
    } else if (!pinger) {
      std::printf("echo discovery_ms=%.1f\n", discovery_ms);
    }
    if (code != 0) std::cerr << "tessera-dds-ping: timed out\n";
    s.flush(Seconds(2));
  }
  signals.stop();
  s.close();
  return code;
}
