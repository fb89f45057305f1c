#include <gtest/gtest.h>

#include "test_support.hpp"

TEST(Cli, UnknownCommandFailsWithUsage) {
  std::string out;
  int rc = tessera::test::run_command(tessera::test::bin("tessera") + " frobnicate", &out);
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("unknown command 'frobnicate'"), std::string::npos) << out;
}
