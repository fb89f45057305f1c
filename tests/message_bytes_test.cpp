// The in-process byte estimate of a protocol message (in_process_driver.hpp message_bytes):
// every field of the core message at its own width plus its arrays' elements.
#include <gtest/gtest.h>

#include <tessera/distributed/in_process_driver.hpp>

namespace tessera {
namespace {

TEST(MessageBytes, AStatusCountsEveryFieldAtItsWidthAndItsArraysElements) {
  // round, sender, phase, near_bound: 4 bytes each; cost, grad_norm_sq, block_grad_norm: 8;
  // the two votes: 1.
  RoundStatusMessage s;
  EXPECT_EQ(message_bytes(s), 4u * 4 + 3 * 8 + 2);
  s.near_bound = 7;  // a count: its value does not change its width
  EXPECT_EQ(message_bytes(s), 42u);
  s.coarse = {1.0, 2.0};
  s.measurement_ids = {3, 5, 9};
  s.weights = {1.0, 0.5, 0.0};
  EXPECT_EQ(message_bytes(s), 42u + 2 * 8 + 3 * 8 + 3 * 8);
}

TEST(MessageBytes, APoseBlockCountsItsFixedFieldsItsIdsAndItsValues) {
  // round, sender, phase, rank, dim: 4 bytes each; kind: 1.
  PoseBlockMessage b;
  EXPECT_EQ(message_bytes(b), 5u * 4 + 1);
  b.rank = 3;
  b.dim = 2;
  b.pose_ids = {4, 11};
  b.data.assign(2 * 3 * 3, 0.25);  // r x (d+1) per pose
  EXPECT_EQ(message_bytes(b), 21u + 2 * 4 + 18 * 8);
}

}  // namespace
}  // namespace tessera
