#include <filesystem>
#include <tessera/io/robot_trajectories.hpp>
#include <tessera/io/text_file_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"
#include "io/tum_line.hpp"

namespace tessera {

std::vector<std::string> write_robot_trajectories(const PoseGraph& graph, const PoseKeys& keys,
                                                  const std::vector<Pose>& poses,
                                                  const std::string& dir) {
  if (poses.size() != graph.num_poses)
    throw InputError(dir, 0,
                     std::to_string(poses.size()) + " poses given for a graph of " +
                         std::to_string(graph.num_poses));
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, 0, "cannot create the folder: " + ec.message());
  const bool stamped = keys.stamps.size() == graph.num_poses && graph.num_poses > 0;
  std::vector<std::vector<std::size_t>> members(keys.num_robots());
  for (std::size_t k = 0; k < graph.num_poses; ++k) members[keys.robot_of(k)].push_back(k);
  std::vector<std::string> paths;
  for (std::size_t r = 0; r < members.size(); ++r) {
    if (members[r].empty()) continue;
    const std::string path = dir + "/robot_" + keys.robot_name(r) + ".tum";
    TextFileWriter file(path);
    std::string& out = file.buffer();
    out += "# robot " + keys.robot_name(r) + ": " + std::to_string(members[r].size()) +
           " poses of " + graph.source + "\n";
    out += stamped ? "# timestamp = pose stamp (s)\n" : std::string(kTumIndexStampsNote) + "\n";
    out += "# timestamp tx ty tz qx qy qz qw\n";
    for (std::size_t k : members[r]) {
      const Pose& p = poses[k];
      if (stamped)
        append_number(out, keys.stamps[k]);
      else
        append_integer(out, keys.index_in_robot(k));
      append_tum_pose(out, p);
      file.maybe_flush();
    }
    file.close();
    paths.push_back(path);
  }
  return paths;
}

}  // namespace tessera
