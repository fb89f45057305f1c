// `--refine-sigma solve|one|every` at the agents' end of its way from `tessera launch` (which
// forwards it to the coordinator, which publishes it in the assignment,
// PartitionAssignment::refine_sigma): RunOptions::refine_sigma sets core's
// NewtonRefineOptions::sigma_factoring, and a restarted agent's checkpoint keeps it (every agent
// must factor Sigma the same way). No process is started here.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "runtime/agent_checkpoint.hpp"
#include "runtime/round_loop.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(RefineSigmaOptions, AgentsFactorSigmaAsTheRunSays) {
  agent::RunOptions o;
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  const SigmaFactoring core_default = NewtonRefineOptions{}.sigma_factoring;
  EXPECT_EQ(agent::distributed_options_of(o).refine.sigma_factoring, core_default);
  o.refine_sigma = "one";
  EXPECT_EQ(agent::distributed_options_of(o).refine.sigma_factoring, SigmaFactoring::kShipFactor);
  o.refine_sigma = "every";
  EXPECT_EQ(agent::distributed_options_of(o).refine.sigma_factoring, SigmaFactoring::kEveryAgent);
  o.refine_sigma = "solve";
  EXPECT_EQ(agent::distributed_options_of(o).refine.sigma_factoring, SigmaFactoring::kShipSolves);
  o.refine_sigma = "two";
  const std::string e = test::input_error_of([&o] { agent::distributed_options_of(o); });
  EXPECT_NE(e.find("refine_sigma"), std::string::npos) << e;
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
