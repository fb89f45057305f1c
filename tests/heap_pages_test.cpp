// The heaps' page size (launch/heap_pages.hpp): `auto` takes 2 MB pages only where the probe
// finds fresh 4 KB pages slow, a user's glibc.malloc.hugetlb wins, and `tessera solve` really runs
// on the chosen heap (the re-executed process has the tunable) and says so in its JSON.

#include "launch/heap_pages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "random_graph.hpp"
#include "test_support.hpp"

namespace tessera::launch {
namespace {

constexpr const char* kThpMadvise = "always [madvise] never";
int g_probes = 0;
double slow_probe() {
  return ++g_probes, 15.0;
}
double fast_probe() {
  return ++g_probes, 2.0;
}

TEST(HeapPages, AutoTakesHugePagesOnlyWhereAFreshPageIsSlow) {
  g_probes = 0;
  const HeapPagesChoice slow = decide_heap_pages(HeapPages::kAuto, "", kThpMadvise, &slow_probe);
  EXPECT_TRUE(slow.huge);
  EXPECT_EQ(slow.name(), "2m");
  EXPECT_DOUBLE_EQ(slow.fresh_page_us, 15.0);
  const HeapPagesChoice fast = decide_heap_pages(HeapPages::kAuto, "", kThpMadvise, &fast_probe);
  EXPECT_FALSE(fast.huge);
  EXPECT_EQ(fast.name(), "4k");
  EXPECT_EQ(g_probes, 2);
  // Other tunables of the user's leave the decision to the probe.
  EXPECT_TRUE(
      decide_heap_pages(HeapPages::kAuto, "glibc.malloc.arena_max=2", kThpMadvise, &slow_probe)
          .huge);
}

TEST(HeapPages, TheUsersHugetlbTunableWinsOverAutoWithoutAProbe) {
  g_probes = 0;
  const HeapPagesChoice off =
      decide_heap_pages(HeapPages::kAuto, "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=0",
                        kThpMadvise, &slow_probe);
  EXPECT_FALSE(off.huge);
  EXPECT_NE(off.reason.find("glibc.malloc.hugetlb=0"), std::string::npos) << off.reason;
  EXPECT_TRUE(
      decide_heap_pages(HeapPages::kAuto, "glibc.malloc.hugetlb=1", kThpMadvise, &fast_probe).huge);
  EXPECT_EQ(g_probes, 0);
}

TEST(HeapPages, ExplicitModesDoNotProbeAndTransparentHugePagesOffMeansSmallPages) {
  g_probes = 0;
  EXPECT_FALSE(decide_heap_pages(HeapPages::kSmall, "", kThpMadvise, &slow_probe).huge);
  EXPECT_TRUE(decide_heap_pages(HeapPages::kHuge, "", kThpMadvise, &fast_probe).huge);
  const HeapPagesChoice never =
      decide_heap_pages(HeapPages::kHuge, "", "always madvise [never]", &slow_probe);
  EXPECT_FALSE(never.huge);
  EXPECT_NE(never.reason.find("off"), std::string::npos) << never.reason;
  EXPECT_FALSE(decide_heap_pages(HeapPages::kAuto, "", "always madvise [never]", &slow_probe).huge);
  EXPECT_EQ(g_probes, 0);
}

TEST(HeapPages, FlagValuesAreCheckedByName) {
  EXPECT_EQ(parse_heap_pages("auto", "--heap-pages"), HeapPages::kAuto);
  EXPECT_EQ(parse_heap_pages("4k", "--heap-pages"), HeapPages::kSmall);
  EXPECT_EQ(parse_heap_pages("2m", "--heap-pages"), HeapPages::kHuge);
  try {
    parse_heap_pages("1g", "option --heap-pages");
    FAIL() << "1g accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("option --heap-pages"), std::string::npos) << e.what();
  }
}

TEST(HeapPages, TheProbeMeasuresAFiniteCostPerPage) {
  const double us = fresh_page_cost_us();
  EXPECT_GT(us, 0.0);
  EXPECT_TRUE(std::isfinite(us));
}

bool thp_available() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(in, text);
  return !text.empty() && text.find("[never]") == std::string::npos;
}

std::string solve_json(const std::string& dir, const std::string& prefix,
                       const std::string& flags) {
  const std::string g = dir + "/g.g2o";
  write_g2o(test::random_pose_graph({2, 60, 30, 0.01, 0.01, 1}), g);
  std::string out;
  EXPECT_EQ(test::run_command(prefix + test::bin("tessera") + " solve " + g + " " + flags +
                                  " --json " + dir + "/r.json 2>&1",
                              &out),
            0)
      << out;
  return test::read_text_file(dir + "/r.json");
}

TEST(HeapPagesCli, SolveRunsOnTheHeapItWasAskedForAndSaysSo) {
  const std::string dir = test::temp_dir();
  // The JSON's heap_pages is read from the solving process's own GLIBC_TUNABLES: "2m" only
  // when the re-executed process has glibc.malloc.hugetlb=1.
  const std::string huge = solve_json(dir, "env -u GLIBC_TUNABLES ", "--heap-pages 2m");
  EXPECT_NE(huge.find(std::string("\"heap_pages\": \"") + (thp_available() ? "2m" : "4k")),
            std::string::npos)
      << huge;
  EXPECT_NE(huge.find("\"fresh_page_us\": null"), std::string::npos) << huge;
  const std::string small = solve_json(dir, "env -u GLIBC_TUNABLES ", "--heap-pages 4k");
  EXPECT_NE(small.find("\"heap_pages\": \"4k\""), std::string::npos) << small;
  // auto probes: a measured cost, whichever size it chose.
  const std::string autom = solve_json(dir, "env -u GLIBC_TUNABLES ", "");
  EXPECT_EQ(autom.find("\"fresh_page_us\": null"), std::string::npos) << autom;
  // A user's tunable is kept: no probe.
  const std::string user = solve_json(dir, "env GLIBC_TUNABLES=glibc.malloc.hugetlb=0 ", "");
  EXPECT_NE(user.find("\"heap_pages\": \"4k\""), std::string::npos) << user;
  EXPECT_NE(user.find("\"fresh_page_us\": null"), std::string::npos) << user;
}

TEST(HeapPagesCli, ABadValueIsAnInputErrorNamingTheFlag) {
  const std::string dir = test::temp_dir();
  const std::string g = dir + "/g.g2o";
  write_g2o(test::random_pose_graph({2, 20, 5, 0.01, 0.01, 1}), g);
  std::string out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g + " --heap-pages 1g 2>&1", &out),
            2);
  EXPECT_NE(out.find("--heap-pages must be auto, 4k or 2m"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::launch
