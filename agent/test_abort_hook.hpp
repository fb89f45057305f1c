#pragma once
// TEST-ONLY: makes an agent abort (SIGABRT from another thread, as Fast DDS's failed
// assertion does in its event thread) at a chosen point of the end of its run, so the tests
// can check how that ends the agent and what launch reports (tests/dds_agent_end_abort_test.cpp).
// Compiled in only when the build has TESSERA_TEST_HOOKS (CMake option, on with the test suite);
// elsewhere test_abort_point() is an empty inline function.
// Set by the environment variable TESSERA_TEST_AGENT_ABORT=WHEN[:ID] (every agent without
// :ID), WHEN one of
//   before-result   after its round loop, before its final estimate is published: the run
//                   is not complete and must fail (exit 134, launch exit 1);
//   after-finished  after the coordinator's FINISHED (the merged result is written): the
//                   cover of cli/session_process.cpp ends the agent with exit 0 and a note.
//
// And TESSERA_TEST_AGENT_KILL=STAGE[@K][:ID] SIGKILLs the agent (a process lost for good, as a
// crash or an OOM kill leaves it) at the K-th (default 1) progress point of a stage after the
// rounds (tests/dds_stage_loss_test.cpp), STAGE one of
//   refinement   a protocol message handled in the Newton refinement;
//   certificate  a protocol message handled in the distributed certificate;
//   rounding     an iteration of the distributed rounding's translation CG.
//
// And TESSERA_TEST_AGENT_HOLD=PATH[:ID] holds the agent just before its result is published
// (test_hold_point, before the `before-result` abort point) until the file PATH exists (at most 120
// s), so a test can keep a run alive, its coordinator answering, until something it starts has
// happened (tests/dds_loss_test.cpp: a restarted process refused while the survivors' run is still
// on, however fast their rounds are).

#include <cstdint>

#include "runtime/stage_progress.hpp"

namespace tessera::agent {

enum class TestAbortPoint { kBeforeResult, kAfterFinished };

#ifdef TESSERA_TEST_HOOKS
/// Aborts the process if TESSERA_TEST_AGENT_ABORT names `at` for agent `id`; else nothing.
void test_abort_point(TestAbortPoint at, std::uint32_t id);
/// Waits while TESSERA_TEST_AGENT_HOLD names, for agent `id`, a file that does not exist yet
/// (at most 120 s); else nothing.
void test_hold_point(std::uint32_t id);
/// Whether TESSERA_TEST_AGENT_KILL is set (the round loop then reports every progress point).
bool test_kill_armed();
/// Called at each progress point of `stage` on agent `id`: SIGKILLs the process at the one
/// TESSERA_TEST_AGENT_KILL names; else nothing.
void test_kill_point(ProgressStage stage, std::uint32_t id);
#else
inline void test_abort_point(TestAbortPoint, std::uint32_t) {}
inline void test_hold_point(std::uint32_t) {}
inline bool test_kill_armed() {
  return false;
}
inline void test_kill_point(ProgressStage, std::uint32_t) {}
#endif

}  // namespace tessera::agent
