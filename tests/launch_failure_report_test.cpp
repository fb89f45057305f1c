// launch's report after a failed run (launch/failure_report.hpp): the same failure of several
// agents shown once, and the exit code that says whether the input was bad.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "launch/failure_report.hpp"

namespace tessera::launch {
namespace {

FailedProcess agent(long id, int code, const std::string& message) {
  const std::string marker = "tessera-agent[" + std::to_string(id) + "]";
  return {"agent " + std::to_string(id), id, code, "    " + marker + ": error: " + message + "\n"};
}

FailedProcess coordinator(int code, const std::string& message) {
  return {"coordinator", -1, code, "    tessera-coordinator: error: " + message + "\n"};
}

TEST(FailureReport, AgentsWithTheSameMessageButTheirOwnIdShareOneEntry) {
  const std::vector<FailedProcess> failed = {
      coordinator(1, "agent 1 aborted run 'r': g.g2o: cannot split 2 poses among 4 robots"),
      agent(0, 2, "g.g2o: cannot split 2 poses among 4 robots"),
      agent(1, 2, "g.g2o: cannot split 2 poses among 4 robots"),
      agent(2, 2, "g.g2o: cannot split 2 poses among 4 robots"),
      agent(3, 2, "g.g2o: cannot split 2 poses among 4 robots")};
  const std::vector<FailureGroup> groups = group_failures(failed);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].label(), "coordinator");
  EXPECT_EQ(groups[1].label(), "agents 0, 1, 2 and 3");
  EXPECT_EQ(groups[1].members.front()->tail, failed[1].tail);  // shown as the first member's
  EXPECT_EQ(exit_code_after_failure(failed), 2);
}

TEST(FailureReport, DifferentMessagesOrExitCodesStayApart) {
  const std::vector<FailedProcess> failed = {
      agent(0, 2, "a.g2o:3: bad value"), agent(1, 2, "a.g2o:9: bad value"),
      agent(2, 134, "a.g2o:3: bad value"), agent(3, 2, "a.g2o:3: bad value")};
  const std::vector<FailureGroup> groups = group_failures(failed);
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0].label(), "agents 0 and 3");
  EXPECT_EQ(groups[1].label(), "agent 1");
  EXPECT_EQ(groups[2].label(), "agent 2");
  // An agent that crashed is not bad input: launch's general failure code.
  EXPECT_EQ(exit_code_after_failure(failed), 1);
}

TEST(FailureReport, TheExitCodeIsTwoOnlyForInputErrors) {
  EXPECT_EQ(exit_code_after_failure({coordinator(2, "option --partition-file: no such file")}), 2);
  EXPECT_EQ(exit_code_after_failure({coordinator(1, "lost agent 1")}), 1);
  EXPECT_EQ(exit_code_after_failure({coordinator(1, "lost agent 1"), agent(1, 137, "")}), 1);
  EXPECT_EQ(exit_code_after_failure({agent(1, 2, "x"), agent(2, 1, "y")}), 1);
  EXPECT_EQ(exit_code_after_failure({}), 1);
}

}  // namespace
}  // namespace tessera::launch
