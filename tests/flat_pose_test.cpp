// The flat pose layout (core/include/tessera/graph/flat_pose.hpp): R column-major then t, padding,
// reading at an offset, and refusing arrays that are too short.

#include <gtest/gtest.h>

#include <stdexcept>
#include <tessera/graph/flat_pose.hpp>

namespace tessera {
namespace {

Pose numbered_pose(int d) {
  // Distinct entries so a transposed or shifted layout shows up.
  Pose p;
  p.R.resize(d, d);
  p.t.resize(d);
  for (int r = 0; r < d; ++r) {
    for (int c = 0; c < d; ++c) p.R(r, c) = 10 * (r + 1) + (c + 1);
    p.t(r) = -(r + 1);
  }
  return p;
}

TEST(FlatPose, SizeIsDTimesDPlusOne) {
  EXPECT_EQ(flat_pose_size(2), 6u);
  EXPECT_EQ(flat_pose_size(3), 12u);
}

TEST(FlatPose, RotationColumnMajorThenTranslation) {
  const Pose p = numbered_pose(3);
  std::vector<double> flat{7.0};  // appends after what is there
  append_flat_pose(flat, p);
  ASSERT_EQ(flat.size(), 1u + 12u);
  EXPECT_EQ(flat[0], 7.0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_EQ(flat[1 + c * 3 + r], p.R(r, c)) << r << "," << c;
  for (int r = 0; r < 3; ++r) EXPECT_EQ(flat[1 + 9 + r], p.t(r));
}

TEST(FlatPose, RoundTripAtAnOffsetIn2dAnd3d) {
  for (int d : {2, 3}) {
    const Pose a = numbered_pose(d);
    const Pose b = Pose::identity(d);
    std::vector<double> flat;
    append_flat_pose(flat, b);
    append_flat_pose(flat, a);
    const Pose back = read_flat_pose(flat, flat_pose_size(d), d);
    EXPECT_EQ(back.dim(), d);
    EXPECT_TRUE(back.R == a.R) << "d=" << d;
    EXPECT_TRUE(back.t == a.t) << "d=" << d;
    EXPECT_TRUE(read_flat_pose(flat, 0, d).R == b.R);
  }
}

TEST(FlatPose, PaddedToAWidthWithZeros) {
  const Pose p = numbered_pose(2);
  std::vector<double> flat;
  append_flat_pose(flat, p, 9);
  append_flat_pose(flat, p, 9);
  ASSERT_EQ(flat.size(), 18u);
  for (std::size_t k = 6; k < 9; ++k) EXPECT_EQ(flat[k], 0.0);
  const Pose second = read_flat_pose(flat, 9, 2);
  EXPECT_TRUE(second.R == p.R);
  EXPECT_TRUE(second.t == p.t);
  EXPECT_THROW(append_flat_pose(flat, p, 5), std::invalid_argument);
}

TEST(FlatPose, TooShortArrayIsRefused) {
  std::vector<double> flat;
  append_flat_pose(flat, numbered_pose(3));
  EXPECT_THROW(read_flat_pose(flat, 1, 3), std::out_of_range);
  EXPECT_THROW(read_flat_pose(flat, 100, 3), std::out_of_range);
  flat.pop_back();
  EXPECT_THROW(read_flat_pose(flat, 0, 3), std::out_of_range);
  EXPECT_NO_THROW(read_flat_pose(flat, 0, 2));
}

}  // namespace
}  // namespace tessera
