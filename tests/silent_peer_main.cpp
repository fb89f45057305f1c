// A peer process for tests/dds_silent_peer_teardown_test.cpp (not a test itself):
//   tessera_test_silent_peer agent RUN_ID DOMAIN HOLD_US [TRANSPORT]
//     joins run RUN_ID on DOMAIN as agent 0 of 1, waits until its endpoints matched the
//     coordinator's (at most 10 s; HOLD_US < 0: does not wait), waits |HOLD_US| microseconds
//     more and leaves without writing anything of the run (a set-up that fails early).
//     Exit code 0, or 3 when it did not match.
//   tessera_test_silent_peer coordinator RUN_ID DOMAIN HOLD_US [TRANSPORT]
//     the coordinator of that run for HOLD_US microseconds, then leaves; prints the Fast DDS
//     shared-memory receive errors it counted (transport/fastdds/shm_receive_watch.hpp).
//     Exit code 0, or 4 when it counted any.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"

int main(int argc, char** argv) {
  using namespace tessera::transport;
  if (argc < 5) {
    std::fprintf(stderr,
                 "usage: tessera_test_silent_peer agent|coordinator RUN_ID DOMAIN HOLD_US "
                 "[TRANSPORT]\n");
    return 2;
  }
  const std::string role = argv[1];
  SessionOptions o;
  o.run_id = argv[2];
  o.domain = std::atoi(argv[3]);
  o.coordinator = role == "coordinator";
  o.agent_id = 0;
  o.num_agents = 1;
  o.lease_s = 3.0;
  if (argc > 5) o.transport = argv[5];
  const long hold = std::atol(argv[4]);
  if (o.coordinator) {
    CoordinatorSession session(o);
    std::printf("coordinator up\n");
    std::fflush(stdout);
    std::this_thread::sleep_for(std::chrono::microseconds(hold));
    session.close(0);
    std::printf("receive failures %llu\n", static_cast<unsigned long long>(shm_receive_failures()));
    return shm_receive_failures() == 0 ? 0 : 4;
  }
  AgentSession session(o);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (hold >= 0 && !session.endpoints_matched() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  std::this_thread::sleep_for(std::chrono::microseconds(hold >= 0 ? hold : -hold));
  const bool matched = hold < 0 || session.endpoints_matched();
  session.close(0);
  std::printf("%s\n", matched ? "matched" : "not matched");
  return matched ? 0 : 3;
}
