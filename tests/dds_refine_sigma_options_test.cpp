// `--refine-sigma one|every` at the agents' end of its way from `tessera launch` (which forwards
// it to the coordinator, which publishes it in the assignment, PartitionAssignment::refine_sigma):
// RunOptions::refine_sigma sets core's NewtonRefineOptions::ship_sigma, and a restarted agent's
// checkpoint keeps it (every agent must factor Sigma the same way). No process is started here.

#include <gtest/gtest.h>

#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "runtime/agent_checkpoint.hpp"
#include "runtime/round_loop.hpp"

namespace tessera {
namespace {

TEST(RefineSigmaOptions, AgentsFactorSigmaAsTheRunSays) {
  agent::RunOptions o;
  const bool core_default = NewtonRefineOptions{}.ship_sigma;
  EXPECT_EQ(agent::distributed_options_of(o).refine.ship_sigma, core_default);
  o.refine_sigma = "one";
  EXPECT_TRUE(agent::distributed_options_of(o).refine.ship_sigma);
  o.refine_sigma = "every";
  EXPECT_FALSE(agent::distributed_options_of(o).refine.ship_sigma);
  o.refine_sigma = "two";
  try {
    agent::distributed_options_of(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("refine_sigma"), std::string::npos) << e.what();
  }
}

TEST(RefineSigmaOptions, ARestartedAgentsCheckpointKeepsIt) {
  agent::AgentLocalData local;
  local.d = 2;
  local.num_poses = 1;
  local.owner = {0};
  local.options.refine_sigma = "one";
  const agent::AgentCheckpoint back =
      agent::decode_checkpoint(agent::encode_checkpoint("sigma", local, {}), "test");
  EXPECT_EQ(back.local.options.refine_sigma, "one");
}

}  // namespace
}  // namespace tessera
