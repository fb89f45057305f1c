// `tessera solve --algorithm centralized --preconditioner auto|tangent|euclidean`: the JSON says
// which preconditioner ran; a bad value is an input error naming the flag.

#include <gtest/gtest.h>

#include <tessera/io/g2o_writer.hpp>

#include "random_graph.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(CentralizedCli, JsonNamesThePreconditionerThatRan) {
  const std::string dir = test::temp_dir();
  const std::string g = dir + "/g.g2o";
  write_g2o(test::random_pose_graph({2, 60, 30, 0.01, 0.01, 1}), g);
  for (const char* p : {"auto", "tangent", "euclidean"}) {
    std::string out;
    ASSERT_EQ(test::run_command(test::bin("tessera") + " solve " + g +
                                    " --algorithm centralized --preconditioner " + p + " --json " +
                                    dir + "/r.json",
                                &out),
              0)
        << out;
    const std::string j = test::read_text_file(dir + "/r.json");
    // A 2D graph's tangent factor is cheap: auto starts with it.
    const std::string expected = std::string(p) == "euclidean" ? "euclidean" : "tangent";
    EXPECT_NE(j.find("\"preconditioner\": \"" + expected + "\""), std::string::npos) << p << j;
    EXPECT_NE(j.find("\"inner_iterations\""), std::string::npos) << j;
    EXPECT_NE(j.find("\"tangent_factorizations\""), std::string::npos) << j;
  }
  std::string out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g +
                                  " --algorithm centralized --preconditioner jacobi",
                              &out),
            2);
  EXPECT_NE(out.find("--preconditioner"), std::string::npos) << out;
  EXPECT_NE(out.find("auto, tangent, euclidean"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera
