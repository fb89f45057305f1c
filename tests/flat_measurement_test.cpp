// The flat layout of a measurement's values (core/include/tessera/graph/flat_measurement.hpp): R
// column-major and t, into separate arrays (the hand-off) or one array (the initialisation
// stage), read back at offsets, short arrays refused.

#include <gtest/gtest.h>

#include <stdexcept>
#include <tessera/graph/flat_measurement.hpp>
#include <tessera/graph/flat_pose.hpp>

namespace tessera {
namespace {

Measurement numbered_measurement(int d) {
  // Distinct entries so a transposed or shifted layout shows up.
  Measurement e;
  e.i = 3;
  e.j = 8;
  e.kappa = 2.5;
  e.tau = 0.75;
  e.R.resize(d, d);
  e.t.resize(d);
  for (int r = 0; r < d; ++r) {
    for (int c = 0; c < d; ++c) e.R(r, c) = 10 * (r + 1) + (c + 1) + 0.125;
    e.t(r) = -(r + 1) - 0.5;
  }
  return e;
}

TEST(FlatMeasurement, SeparateArraysHoldRColumnMajorAndT) {
  const Measurement e = numbered_measurement(3);
  std::vector<double> R{1.0}, t{2.0, 3.0};  // appends after what is there
  append_measurement_rt(R, t, e);
  ASSERT_EQ(R.size(), 1u + 9u);
  ASSERT_EQ(t.size(), 2u + 3u);
  EXPECT_EQ(R[0], 1.0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_EQ(R[1 + c * 3 + r], e.R(r, c)) << r << "," << c;
  for (int r = 0; r < 3; ++r) EXPECT_EQ(t[2 + r], e.t(r));
}

TEST(FlatMeasurement, OneArrayIsTheFlatPoseOfRAndT) {
  for (int d : {2, 3}) {
    const Measurement e = numbered_measurement(d);
    std::vector<double> one{9.0};
    append_measurement_rt(one, one, e);
    std::vector<double> pose{9.0};
    append_flat_pose(pose, Pose{e.R, e.t});
    EXPECT_EQ(one, pose) << "d = " << d;
  }
}

TEST(FlatMeasurement, RoundTripAtOffsetsInBothForms) {
  for (int d : {2, 3}) {
    const Measurement a = numbered_measurement(d);
    Measurement b = numbered_measurement(d);
    b.R *= -1.0;
    b.t *= 3.0;
    // Separate arrays, two measurements: the second starts at d*d and d.
    std::vector<double> R, t;
    append_measurement_rt(R, t, a);
    append_measurement_rt(R, t, b);
    Measurement back;
    back.i = 5;
    read_measurement_rt(R, static_cast<std::size_t>(d * d), t, static_cast<std::size_t>(d), d,
                        back);
    EXPECT_EQ(back.R, b.R) << "d = " << d;
    EXPECT_EQ(back.t, b.t) << "d = " << d;
    EXPECT_EQ(back.i, 5u) << "i, j, kappa, tau are not touched";
    // One array after a 4-value header, as the initialisation stage writes it.
    std::vector<double> one{1, 2, 3, 4};
    append_measurement_rt(one, one, a);
    Measurement back_one;
    read_measurement_rt(one, 4, one, 4 + static_cast<std::size_t>(d * d), d, back_one);
    EXPECT_EQ(back_one.R, a.R) << "d = " << d;
    EXPECT_EQ(back_one.t, a.t) << "d = " << d;
  }
}

TEST(FlatMeasurement, ShortArraysAreRefused) {
  const Measurement e = numbered_measurement(2);
  std::vector<double> R, t;
  append_measurement_rt(R, t, e);
  Measurement back;
  EXPECT_THROW(read_measurement_rt(R, 1, t, 0, 2, back), std::out_of_range);
  EXPECT_THROW(read_measurement_rt(R, 0, t, 1, 2, back), std::out_of_range);
  EXPECT_THROW(read_measurement_rt(R, 10, t, 0, 2, back), std::out_of_range);
  EXPECT_THROW(read_measurement_rt(R, 0, t, 0, 3, back), std::out_of_range);
  EXPECT_NO_THROW(read_measurement_rt(R, 0, t, 0, 2, back));
}

}  // namespace
}  // namespace tessera
