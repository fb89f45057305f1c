// The coordinator's structure (coordinator/run_structure.hpp) comes out in the measurements'
// input order whatever order the announcements arrive in, so it partitions and every agent
// lays out the graph exactly as `tessera solve` does. No participant, no domain.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tessera/generate/generator.hpp>
#include <tessera/util/input_error.hpp>

#include "announcement_support.hpp"
#include "coordinator/run_structure.hpp"
#include "runtime/local_share.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

using test::announcements_of;

PoseGraph graph() {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 300;
  o.num_robots = 4;
  o.seed = 6;
  return generate_pose_graph(o).graph;
}

TEST(DdsStructureOrder, StructureIsInInputOrderWhateverTheArrivalOrder) {
  const PoseGraph g = graph();
  std::vector<wire::AgentAnnouncement> anns = announcements_of(g, 4);
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    std::shuffle(anns.begin(), anns.end(), rng);
    const coordinator::RunStructure rs = coordinator::merge_announcements(anns, 4, "r");
    ASSERT_EQ(rs.edge_i.size(), g.measurements.size());
    for (std::size_t k = 0; k < g.measurements.size(); ++k) {
      ASSERT_EQ(rs.edge_i[k], g.measurements[k].i) << "measurement " << k;
      ASSERT_EQ(rs.edge_j[k], g.measurements[k].j) << "measurement " << k;
    }
  }
  // The measurements of one robot are not contiguous in the file: agent order would differ.
  const coordinator::RunStructure rs = coordinator::merge_announcements(anns, 4, "r");
  std::vector<std::uint32_t> agent_order;
  for (std::uint32_t k = 0; k < 4; ++k)
    for (const auto& a : anns)
      if (a.agent_id() == k)
        agent_order.insert(agent_order.end(), a.edge_i().begin(), a.edge_i().end());
  EXPECT_NE(agent_order, rs.edge_i);
}

TEST(DdsStructureOrder, AMeasurementAnnouncedTwiceOrWithoutIndexIsAnError) {
  const PoseGraph g = graph();
  std::vector<wire::AgentAnnouncement> anns = announcements_of(g, 4);
  anns[2].edge_index()[0] = anns[1].edge_index()[0];
  EXPECT_NE(test::input_error_of([&] {
              coordinator::merge_announcements(anns, 4, "r");
            }).find("agents 1 and 2 both announced measurement #"),
            std::string::npos);
  anns = announcements_of(g, 4);
  anns[3].edge_index().pop_back();
  EXPECT_THROW(coordinator::merge_announcements(anns, 4, "r"), InputError);
}

}  // namespace
}  // namespace tessera
