#include "launch/dpgo_csv_input.hpp"

#include <algorithm>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "robot_files.hpp"

namespace tessera::launch {

std::string dpgo_csv_as_robot_files(const std::string& graph, long agents,
                                    const std::string& work) {
  if (!is_dpgo_csv(graph)) return "";
  const DpgoCsvGraph csv = read_dpgo_csv(graph);
  const std::size_t robots =
      csv.robot_of.empty()
          ? 0
          : static_cast<std::size_t>(*std::max_element(csv.robot_of.begin(), csv.robot_of.end())) +
                1;
  if (static_cast<std::size_t>(agents) != robots)
    throw InputError(graph, 0,
                     "holds " + std::to_string(robots) + " robots but --agents is " +
                         std::to_string(agents) + " (one agent per robot)");
  // The whole graph as g2o (the writer's weights read back as the CSV's kappa and tau), then
  // split by the CSV's robots.
  const std::string whole = work + "/dpgo.g2o";
  write_g2o(csv.graph, whole);
  std::vector<std::size_t> robot_of(csv.robot_of.begin(), csv.robot_of.end());
  const std::string dir = work + "/robots";
  cli::write_robot_files(whole, robot_of, robots, dir, csv.known_inlier);
  return dir;
}

}  // namespace tessera::launch
