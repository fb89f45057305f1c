#include "runtime/local_dump.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <tessera/util/input_error.hpp>

namespace tessera::agent {

namespace {

void num(std::string& out, double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), " %.17g", x);
  out += buf;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError(path, 0, "cannot open for writing");
  f << text;
  if (!f) throw InputError(path, 0, "write failed");
}

}  // namespace

void write_local_dump(const AgentLocalData& local, const std::string& path) {
  std::string out = "AGENT " + std::to_string(local.agent_id) + " " +
                    std::to_string(local.num_agents) + " " + std::to_string(local.d) + " " +
                    std::to_string(local.num_poses) + "\n";
  out += "STRUCTURE " + std::to_string(local.structure.size()) + "\n";
  for (std::uint32_t id : local.owned) out += "OWNED " + std::to_string(id) + "\n";
  for (std::size_t k = 0; k < local.initial.size(); ++k) {
    out += "POSE " + std::to_string(local.owned[k]);
    const Pose& p = local.initial[k];
    for (int c = 0; c < local.d; ++c)
      for (int r = 0; r < local.d; ++r) num(out, p.R(r, c));
    for (int r = 0; r < local.d; ++r) num(out, p.t(r));
    out += "\n";
  }
  for (std::size_t k = 0; k < local.measurements.size(); ++k) {
    const Measurement& m = local.measurements[k];
    out += "MEAS " + std::to_string(local.measurement_index[k]) + " " + std::to_string(m.i) + " " +
           std::to_string(m.j);
    num(out, m.kappa);
    num(out, m.tau);
    for (int c = 0; c < local.d; ++c)
      for (int r = 0; r < local.d; ++r) num(out, m.R(r, c));
    for (int r = 0; r < local.d; ++r) num(out, m.t(r));
    out += "\n";
  }
  write_text(path, out);
}

void write_vertices_g2o(const std::vector<std::uint32_t>& ids, const std::vector<Pose>& poses,
                        int d, const std::string& path) {
  std::string out;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const Pose& p = poses[k];
    if (d == 2) {
      out += "VERTEX_SE2 " + std::to_string(ids[k]);
      num(out, p.t(0));
      num(out, p.t(1));
      num(out, std::atan2(p.R(1, 0), p.R(0, 0)));
    } else {
      out += "VERTEX_SE3:QUAT " + std::to_string(ids[k]);
      Eigen::Matrix3d R = p.R;
      Eigen::Quaterniond q(R);
      q.normalize();
      if (q.w() < 0) q.coeffs() *= -1.0;
      for (int r = 0; r < 3; ++r) num(out, p.t(r));
      num(out, q.x());
      num(out, q.y());
      num(out, q.z());
      num(out, q.w());
    }
    out += "\n";
  }
  write_text(path, out);
}

}  // namespace tessera::agent
