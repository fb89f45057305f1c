#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <tessera/graph/connectivity.hpp>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>

#include "io/rotation_text.hpp"

namespace tessera {
namespace {

const char* const kHeader =
    "robot_src,pose_src,robot_dst,pose_dst,qx,qy,qz,qw,tx,ty,tz,kappa,tau,is_known_inlier,weight";
constexpr std::size_t kFields = 15;

struct Row {
  long robot_src, pose_src, robot_dst, pose_dst;
  double q[4], t[3], kappa, tau;
  bool known;
};

bool is_file(const std::string& p) {
  struct stat s {};
  return stat(p.c_str(), &s) == 0 && S_ISREG(s.st_mode);
}
bool is_dir(const std::string& p) {
  struct stat s {};
  return stat(p.c_str(), &s) == 0 && S_ISDIR(s.st_mode);
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && (s[b] == ' ' || s[b] == '\t')) ++b;
  return s.substr(b);
}

double number(const std::string& text, const char* field, const std::string& file,
              std::size_t line) {
  const std::string s = trim(text);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v))
    throw InputError(file, line, std::string(field) + " '" + s + "' is not a finite number");
  return v;
}

long index(const std::string& text, const char* field, const std::string& file, std::size_t line) {
  const double v = number(text, field, file, line);
  if (v < 0 || v != std::floor(v) || v > 1e15)
    throw InputError(file, line,
                     std::string(field) + " '" + trim(text) + "' is not an integer >= 0");
  return static_cast<long>(v);
}

std::vector<Row> read_file(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file, 0, "cannot open for reading");
  std::vector<Row> rows;
  std::string text;
  std::size_t line = 0;
  bool header = false;
  while (std::getline(in, text)) {
    ++line;
    text = trim(text);
    if (text.empty()) continue;
    if (!header) {
      std::string compact;
      for (char c : text)
        if (c != ' ' && c != '\t') compact += c;
      if (compact != kHeader)
        throw InputError(file, line, std::string("expected the header line '") + kHeader + "'");
      header = true;
      continue;
    }
    std::vector<std::string> f;
    std::stringstream ss(text);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    if (!text.empty() && text.back() == ',') f.emplace_back();
    if (f.size() != kFields)
      throw InputError(file, line,
                       "expected " + std::to_string(kFields) + " comma-separated fields, found " +
                           std::to_string(f.size()));
    Row r{};
    r.robot_src = index(f[0], "robot_src", file, line);
    r.pose_src = index(f[1], "pose_src", file, line);
    r.robot_dst = index(f[2], "robot_dst", file, line);
    r.pose_dst = index(f[3], "pose_dst", file, line);
    const char* qn[] = {"qx", "qy", "qz", "qw"};
    for (int k = 0; k < 4; ++k) r.q[k] = number(f[4 + k], qn[k], file, line);
    const char* tn[] = {"tx", "ty", "tz"};
    for (int k = 0; k < 3; ++k) r.t[k] = number(f[8 + k], tn[k], file, line);
    r.kappa = number(f[11], "kappa", file, line);
    r.tau = number(f[12], "tau", file, line);
    const double known = number(f[13], "is_known_inlier", file, line);
    number(f[14], "weight", file, line);  // dpgo's own GNC weight: checked, not used
    if (!(r.kappa > 0)) throw InputError(file, line, "kappa must be > 0");
    if (!(r.tau > 0)) throw InputError(file, line, "tau must be > 0");
    if (known != 0 && known != 1) throw InputError(file, line, "is_known_inlier must be 0 or 1");
    r.known = known == 1;
    const double qnorm =
        std::sqrt(r.q[0] * r.q[0] + r.q[1] * r.q[1] + r.q[2] * r.q[2] + r.q[3] * r.q[3]);
    if (!(qnorm > 1e-12)) throw InputError(file, line, "the quaternion is zero");
    for (double& c : r.q) c /= qnorm;
    if (r.robot_src == r.robot_dst && r.pose_src == r.pose_dst)
      throw InputError(file, line, "a measurement from a pose to itself");
    rows.push_back(r);
  }
  if (!header) throw InputError(file, 0, "empty file (no header line)");
  return rows;
}

}  // namespace

bool is_dpgo_csv(const std::string& path) {
  if (is_dir(path)) return is_file(path + "/robot0/measurements.csv");
  return path.size() >= 4 && path.compare(path.size() - 4, 4, ".csv") == 0;
}

DpgoCsvGraph read_dpgo_csv(const std::string& path) {
  std::vector<std::vector<Row>> files;
  if (is_dir(path)) {
    for (int k = 0; is_file(path + "/robot" + std::to_string(k) + "/measurements.csv"); ++k)
      files.push_back(read_file(path + "/robot" + std::to_string(k) + "/measurements.csv"));
    if (files.empty()) throw InputError(path, 0, "no robot0/measurements.csv in this folder");
  } else {
    files.push_back(read_file(path));
  }
  // Poses per robot: 1 + the largest index seen.
  std::vector<long> size;
  for (const auto& rows : files)
    for (const Row& r : rows)
      for (auto [robot, pose] :
           {std::pair{r.robot_src, r.pose_src}, std::pair{r.robot_dst, r.pose_dst}}) {
        if (static_cast<std::size_t>(robot) >= size.size())
          size.resize(static_cast<std::size_t>(robot) + 1, 0);
        size[static_cast<std::size_t>(robot)] =
            std::max(size[static_cast<std::size_t>(robot)], pose + 1);
      }
  std::vector<std::size_t> offset(size.size() + 1, 0);
  for (std::size_t r = 0; r < size.size(); ++r)
    offset[r + 1] = offset[r] + static_cast<std::size_t>(size[r]);

  DpgoCsvGraph out;
  out.graph.d = 3;
  out.graph.num_poses = offset.back();
  out.graph.source = path;
  for (std::size_t r = 0; r < size.size(); ++r)
    out.robot_of.insert(out.robot_of.end(), static_cast<std::size_t>(size[r]), static_cast<int>(r));
  std::set<std::tuple<long, long, long, long>> seen;
  for (const auto& rows : files)
    for (const Row& r : rows) {
      if (!seen.insert({r.robot_src, r.pose_src, r.robot_dst, r.pose_dst}).second) {
        ++out.duplicates;
        continue;
      }
      Measurement m;
      m.i = offset[static_cast<std::size_t>(r.robot_src)] + static_cast<std::size_t>(r.pose_src);
      m.j = offset[static_cast<std::size_t>(r.robot_dst)] + static_cast<std::size_t>(r.pose_dst);
      m.R = rotation_from_quaternion(r.q[0], r.q[1], r.q[2], r.q[3]);
      m.t = Eigen::Vector3d(r.t[0], r.t[1], r.t[2]);
      m.kappa = r.kappa;
      m.tau = r.tau;
      out.graph.measurements.push_back(std::move(m));
      out.known_inlier.push_back(r.known);
    }
  if (out.graph.num_poses < 2) throw InputError(path, 0, "fewer than two poses");
  const std::size_t parts = count_components(out.graph);
  if (parts > 1)
    throw InputError(
        path, 0,
        "the measurements do not connect the poses (" + std::to_string(parts) + " separate parts)");
  return out;
}

}  // namespace tessera
