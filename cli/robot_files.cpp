#include "robot_files.hpp"

#include <dirent.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tessera/util/input_error.hpp>

#include "generate/robot_ranges.hpp"

namespace tessera::cli {

std::vector<std::string> write_robot_files(const std::string& whole, std::size_t num_poses,
                                           std::size_t robots, const std::string& dir) {
  if (robots < 1 || robots > num_poses)
    throw InputError("option --split: needs 1 <= robots <= poses");
  return write_robot_files(whole, robot_of_poses(num_poses, robots), robots, dir);
}

std::vector<std::string> write_robot_files(const std::string& whole,
                                           const std::vector<std::size_t>& robot,
                                           std::size_t robots, const std::string& dir,
                                           const std::vector<bool>& known_inlier) {
  const std::size_t num_poses = robot.size();
  // Each robot's range [begin[r], begin[r + 1]).
  std::vector<std::size_t> begin(robots + 1, num_poses);
  for (std::size_t id = num_poses; id-- > 0;) {
    if (robot[id] >= robots || (id > 0 && robot[id - 1] > robot[id]))
      throw InputError(whole, 0, "robots must own contiguous id ranges in robot order");
    begin[robot[id]] = id;
  }
  for (std::size_t r = robots; r-- > 0;) begin[r] = std::min(begin[r], begin[r + 1]);
  if (mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw InputError(dir, 0, std::string("cannot create the folder: ") + std::strerror(errno));
  std::vector<std::string> body(robots);
  std::vector<std::string> index(robots), known(robots);
  std::ifstream in(whole);
  if (!in) throw InputError(whole, 0, "cannot read the graph back");
  std::size_t edge = 0, line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    std::istringstream t(line);
    std::string tag;
    std::size_t id = 0;
    if (!(t >> tag) || tag[0] == '#') continue;
    if (!(t >> id) || id >= num_poses)
      throw InputError(whole, line_no, "unexpected line while splitting");
    body[robot[id]] += line + "\n";  // VERTEX: its pose; EDGE: its first endpoint's robot
    if (tag.rfind("EDGE", 0) == 0) {
      if (edge < known_inlier.size() && known_inlier[edge])
        known[robot[id]] += " " + std::to_string(edge);
      index[robot[id]] += " " + std::to_string(edge++);
    }
  }
  const std::size_t width = std::to_string(robots - 1).size();
  std::vector<std::string> paths;
  for (std::size_t r = 0; r < robots; ++r) {
    std::string name = std::to_string(r);
    name.insert(0, width - name.size(), '0');
    const std::string path = dir + "/robot" + name + ".g2o";
    std::ofstream out(path);
    out << "# tessera-robot poses " << begin[r] << " " << begin[r + 1] << "\n"
        << "# tessera-measurement-index" << index[r] << "\n"
        << (known[r].empty() ? "" : "# tessera-known-inliers" + known[r] + "\n") << "# robot " << r
        << " of " << robots << " of " << whole
        << ": its poses and the measurements it recorded (global ids)\n"
        << body[r];
    if (!out) throw InputError(path, 0, "cannot write the file");
    paths.push_back(path);
  }
  return paths;
}

}  // namespace tessera::cli

namespace tessera::cli {

std::vector<std::string> robot_files_of(const std::string& graph) {
  std::vector<std::string> out;
  struct stat st {};
  if (stat(graph.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    DIR* d = opendir(graph.c_str());
    if (!d) throw InputError(graph, 0, "cannot read the folder");
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".g2o") == 0)
        out.push_back(graph + "/" + name);
    }
    closedir(d);
    std::sort(out.begin(), out.end());
    if (out.empty()) throw InputError(graph, 0, "the folder holds no .g2o files");
    return out;
  }
  if (graph.find(',') == std::string::npos) return out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = graph.find(',', start);
    const std::string item = graph.substr(start, comma - start);
    if (item.empty()) throw InputError("launch: empty file name in the list '" + graph + "'");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace tessera::cli
