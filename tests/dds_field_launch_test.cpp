// `tessera launch` on a GTSAM-keyed multi-robot file over DDS: the sequential baseline is
// each robot's own poses, and the outputs (--out, --tum-dir, --plot) use the input's ids,
// stamps and frame. DDS domain 20.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <tessera/graph/pose_keys.hpp>
#include <tessera/io/g2o_reader.hpp>

#include "test_support.hpp"

namespace {

using tessera::test::bin;
using tessera::test::contains;
using tessera::test::read_text_file;
using tessera::test::run_command;
using tessera::test::temp_dir;

TEST(DdsFieldLaunch, GtsamFileRunsPerRobotAndWritesTheInputsIdsAndStamps) {
  const std::string dir = temp_dir();
  const std::string g = dir + "/g.g2o", truth = dir + "/truth.g2o", st = dir + "/st.txt";
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " generate --kind grid3d --poses 90 --robots 3 --keys " +
                            "gtsam --stamps " + st + " --truth " + truth + " --out " + g,
                        &out),
            0)
      << out;
  std::string info;
  ASSERT_EQ(run_command(bin("tessera") + " info " + g + " --json -", &info), 0) << info;
  const auto at = info.rfind("\"inter_robot_closures\": ");  // the team's, after "robots"
  ASSERT_NE(at, std::string::npos) << info;
  const std::string inter = info.substr(at + 24, info.find_first_of(",\n", at + 24) - at - 24);

  ASSERT_EQ(run_command(bin("tessera") + " launch " + g +
                            " --agents 3 --partition sequential --grad-tol 0.001 --stamps " + st +
                            " --out " + dir + "/opt.g2o --tum-dir " + dir + "/tum --plot " + dir +
                            "/fig.png --domain 20 --timeout 120 2>&1",
                        &out),
            0)
      << out;
  // Each robot its own poses: the cut is exactly the inter-robot measurements.
  EXPECT_TRUE(contains(out, "\"cut_edges\": " + inter + ",")) << out;
  for (const char* r : {"a", "b", "c"}) {
    const std::string text = read_text_file(dir + "/tum/robot_" + r + ".tum");
    EXPECT_TRUE(contains(text, "# robot " + std::string(r) + ": 30 poses")) << text;
    EXPECT_TRUE(contains(text, "\n1002.9 ")) << text;  // pose 29 at 1000 + 0.1 * 29
  }
  const auto in = tessera::read_g2o_file(g), res = tessera::read_g2o_file(dir + "/opt.g2o");
  EXPECT_EQ(res.keys.ids, in.keys.ids);
  EXPECT_NEAR((res.graph.initial[0].t - in.graph.initial[0].t).norm(), 0, 1e-12);
  EXPECT_GT(std::filesystem::file_size(dir + "/fig.png"), 10000u);
  // The answer is close to the centralized one: its ATE against the truth is that of the
  // certified optimum (same ids, matched by index).
  std::string a, b;
  ASSERT_EQ(run_command(bin("tessera") + " solve " + g + " --out " + dir + "/c.g2o", &a), 0) << a;
  ASSERT_EQ(
      run_command(bin("tessera") + " eval " + dir + "/opt.g2o " + dir + "/c.g2o --json -", &b), 0)
      << b;
  const auto rm = b.find("\"rmse\": ");
  ASSERT_NE(rm, std::string::npos) << b;
  EXPECT_LT(std::stod(b.substr(rm + 8)), 0.05) << b;
}

}  // namespace
