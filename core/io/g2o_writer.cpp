#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/information_weights.hpp>
#include <tessera/io/text_file_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"
#include "io/rotation_text.hpp"

namespace tessera {
namespace {

void append_numbers(std::string& out, const double* x, int count) {
  for (int k = 0; k < count; ++k) {
    out += ' ';
    append_number(out, x[k]);
  }
}

// "x y theta" (2D) or "x y z qx qy qz qw" (3D).
void append_pose_fields(std::string& out, const Eigen::MatrixXd& R, const Eigen::VectorXd& t) {
  append_numbers(out, t.data(), static_cast<int>(t.size()));
  if (t.size() == 2) {
    out += ' ';
    append_number(out, planar_angle(R));
  } else {
    auto q = unit_quaternion(R);
    append_numbers(out, q.data(), 4);
  }
}

void check_writable(const PoseGraph& graph, const PoseKeys& keys, const std::vector<Pose>& poses,
                    const std::string& path) {
  if (graph.d != 2 && graph.d != 3)
    throw InputError(path, 0, "cannot write a graph of dimension " + std::to_string(graph.d));
  if (!keys.ids.empty() && keys.ids.size() != graph.num_poses)
    throw InputError(path, 0, "the graph's id list does not have one id per pose");
  if (!poses.empty() && poses.size() != graph.num_poses)
    throw InputError(path, 0,
                     std::to_string(poses.size()) + " vertex poses given for a graph of " +
                         std::to_string(graph.num_poses) + " poses");
  for (const auto& p : poses)
    if (p.dim() != graph.d || p.R.rows() != graph.d || p.R.cols() != graph.d)
      throw InputError(path, 0, "a vertex pose does not match the graph dimension");
  for (const auto& m : graph.measurements)
    if (m.dim() != graph.d || m.R.rows() != graph.d || m.R.cols() != graph.d)
      throw InputError(path, 0, "a measurement does not match the graph dimension");
}

}  // namespace

void write_g2o(const PoseGraph& graph, const std::vector<Pose>& poses, const std::string& path) {
  write_g2o(graph, PoseKeys{}, poses, path);
}

void write_g2o(const PoseGraph& graph, const PoseKeys& keys, const std::vector<Pose>& poses,
               const std::string& path) {
  check_writable(graph, keys, poses, path);
  const bool planar = graph.d == 2;
  const char* vertex_tag = planar ? "VERTEX_SE2 " : "VERTEX_SE3:QUAT ";
  const char* edge_tag = planar ? "EDGE_SE2 " : "EDGE_SE3:QUAT ";
  const int info_size = information_upper_size(graph.d);

  TextFileWriter file(path);
  std::string& out = file.buffer();
  for (std::size_t id = 0; id < poses.size(); ++id) {
    out += vertex_tag;
    append_integer(out, keys.id(id));
    append_pose_fields(out, poses[id].R, poses[id].t);
    out += '\n';
    file.maybe_flush();
  }
  for (const auto& m : graph.measurements) {
    out += edge_tag;
    append_integer(out, keys.id(m.i));
    out += ' ';
    append_integer(out, keys.id(m.j));
    append_pose_fields(out, m.R, m.t);
    auto info = information_from_weights(graph.d, m.kappa, m.tau);
    append_numbers(out, info.data(), info_size);
    out += '\n';
    file.maybe_flush();
  }
  if (keys.fixed && !poses.empty()) {
    out += "FIX ";
    append_integer(out, keys.id(*keys.fixed));
    out += '\n';
  }
  file.close();
}

void write_g2o(const PoseGraph& graph, const std::string& path) {
  write_g2o(graph, graph.initial, path);
}

}  // namespace tessera
