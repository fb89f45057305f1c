#include "runtime/robot_file.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

namespace tessera::agent {

namespace {

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

std::uint64_t parse_id(const std::string& path, std::size_t line, const std::string& text,
                       const char* what) {
  std::uint64_t v = 0;
  std::size_t used = 0;
  try {
    v = std::stoull(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || text[0] == '-')
    throw InputError(path, line,
                     std::string(what) + " '" + text + "' is not a non-negative integer");
  return v;
}

bool is_header(const std::vector<std::string>& t, const char* name) {
  return t.size() >= 2 && t[0] == "#" && t[1] == name;
}

}  // namespace

bool is_robot_file(const std::string& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    const auto t = tokens(line);
    if (t.empty()) continue;
    if (t[0][0] != '#') return false;  // headers come before the first record
    if (is_header(t, "tessera-robot")) return true;
  }
  return false;
}

RobotShare read_robot_file(const std::string& path, std::uint32_t robot) {
  // One copy of the file's text at a time (its lines, then the reader's text, then the graph):
  // the reading is an agent's first memory peak, and what it frees stays in the agent's heap.
  std::vector<std::string> lines;
  {
    std::ifstream in(path);
    if (!in) throw InputError(path, 0, "cannot open the file");
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  bool have_range = false;
  std::uint64_t begin = 0, end = 0;
  bool have_index = false;
  std::vector<std::uint64_t> index;
  std::vector<std::uint64_t> known;  // '# tessera-known-inliers': positions of flagged ones
  std::size_t known_line = 0;
  struct Record {
    std::size_t line;  // 0-based; its tokens are read again from lines[line] when needed
    bool vertex;
  };
  std::vector<Record> records;
  std::vector<std::uint64_t> vertex_ids;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    auto t = tokens(lines[k]);
    if (t.empty()) continue;
    if (t[0][0] == '#') {
      if (is_header(t, "tessera-robot")) {
        if (t.size() != 5 || t[2] != "poses")
          throw InputError(path, k + 1, "expected '# tessera-robot poses BEGIN END'");
        begin = parse_id(path, k + 1, t[3], "BEGIN");
        end = parse_id(path, k + 1, t[4], "END");
        if (end <= begin) throw InputError(path, k + 1, "the robot's pose range is empty");
        have_range = true;
      } else if (is_header(t, "tessera-known-inliers")) {
        known_line = k + 1;
        for (std::size_t c = 2; c < t.size(); ++c)
          known.push_back(parse_id(path, k + 1, t[c], "known-inlier measurement index"));
      } else if (is_header(t, "tessera-measurement-index")) {
        have_index = true;
        for (std::size_t c = 2; c < t.size(); ++c)
          index.push_back(parse_id(path, k + 1, t[c], "measurement index"));
      }
      lines[k].clear();  // comments stay out of the reader (line numbers are kept)
      continue;
    }
    const bool vertex = t[0].rfind("VERTEX", 0) == 0, edge = t[0].rfind("EDGE", 0) == 0;
    if (!vertex && !edge) continue;  // FIX or an unknown tag: the reader decides
    const std::size_t ids = vertex ? 1 : 2;
    if (t.size() <= ids) continue;  // the reader reports the short line
    if (vertex) vertex_ids.push_back(parse_id(path, k + 1, t[1], "pose id"));
    records.push_back({k, vertex});
  }
  if (!have_range) {
    if (vertex_ids.empty())
      throw InputError(path, 0,
                       "a robot's own file needs '# tessera-robot poses BEGIN END' or VERTEX lines "
                       "for its poses (to know which pose ids are its own)");
    begin = *std::min_element(vertex_ids.begin(), vertex_ids.end());
    end = *std::max_element(vertex_ids.begin(), vertex_ids.end()) + 1;
  }
  if (end > 0xFFFFFFFFull) throw InputError(path, 0, "pose ids beyond 32 bits");
  auto own = [&](std::uint64_t id) { return id >= begin && id < end; };
  for (std::uint64_t id : vertex_ids)
    if (!own(id))
      throw InputError(path, 0,
                       "VERTEX " + std::to_string(id) + " is not one of this robot's poses " +
                           std::to_string(begin) + ".." + std::to_string(end - 1) +
                           " (a robot's file holds VERTEX lines of its own poses only)");
  if (!vertex_ids.empty() && vertex_ids.size() != end - begin)
    throw InputError(path, 0,
                     "VERTEX lines for " + std::to_string(vertex_ids.size()) + " of the robot's " +
                         std::to_string(end - begin) + " poses " + std::to_string(begin) + ".." +
                         std::to_string(end - 1) + " (all or none)");

  // Compact ids for the reader: own poses first (id - begin), then the other robots' poses
  // this file references, ascending.
  std::map<std::uint64_t, std::uint64_t> foreign;
  std::vector<bool> used(end - begin, !vertex_ids.empty());
  std::size_t edges = 0;
  for (const auto& r : records) {
    if (r.vertex) continue;
    ++edges;
    const auto tok = tokens(lines[r.line]);
    const std::uint64_t i = parse_id(path, r.line + 1, tok[1], "pose id");
    const std::uint64_t j = parse_id(path, r.line + 1, tok[2], "pose id");
    if (!own(i) && !own(j))
      throw InputError(path, r.line + 1,
                       "measurement " + std::to_string(i) + "-" + std::to_string(j) +
                           " touches none of this robot's poses " + std::to_string(begin) + ".." +
                           std::to_string(end - 1));
    for (std::uint64_t id : {i, j}) {
      if (own(id))
        used[id - begin] = true;
      else
        foreign.emplace(id, 0);
    }
  }
  if (edges == 0) throw InputError(path, 0, "a robot's own file needs at least one EDGE line");
  for (std::uint64_t k = 0; k < used.size(); ++k)
    if (!used[k])
      throw InputError(path, 0,
                       "pose " + std::to_string(begin + k) +
                           " of this robot appears on no line (no VERTEX lines, no measurement)");
  std::uint64_t next = end - begin;
  std::vector<std::uint64_t> global(end - begin);
  for (std::uint64_t k = 0; k < global.size(); ++k) global[k] = begin + k;
  for (auto& [id, c] : foreign) {
    c = next++;
    global.push_back(id);
  }
  auto compact = [&](std::uint64_t id) { return own(id) ? id - begin : foreign.at(id); };
  bool d2 = false;
  for (const auto& r : records) {
    auto tok = tokens(lines[r.line]);
    d2 = d2 || tok[0].find("SE2") != std::string::npos;
    const std::size_t ids = r.vertex ? 1 : 2;
    for (std::size_t c = 1; c <= ids; ++c)
      tok[c] = std::to_string(compact(parse_id(path, r.line + 1, tok[c], "pose id")));
    std::string l;
    for (const auto& t : tok) l += (l.empty() ? "" : " ") + t;
    lines[r.line] = std::move(l);
  }
  std::vector<Record>().swap(records);
  std::string text;
  {
    std::size_t size = 0;
    for (const auto& l : lines) size += l.size() + 1;
    text.reserve(size);
  }
  for (auto& l : lines) {
    text += l;
    text += '\n';
    std::string().swap(l);
  }
  std::vector<std::string>().swap(lines);
  if (!vertex_ids.empty())  // the reader wants a VERTEX for every endpoint: placeholders
    for (const auto& [id, c] : foreign)
      text += (d2 ? "VERTEX_SE2 " + std::to_string(c) + " 0 0 0\n"
                  : "VERTEX_SE3:QUAT " + std::to_string(c) + " 0 0 0 0 0 0 1\n");
  G2oReadOptions opt;
  opt.allow_disconnected = true;  // other robots' poses are missing by nature
  PoseGraph g = read_g2o_text(text, path, opt).graph;
  std::string().swap(text);

  if (have_index && index.size() != g.measurements.size())
    throw InputError(path, 0,
                     "'# tessera-measurement-index' lists " + std::to_string(index.size()) +
                         " positions for " + std::to_string(g.measurements.size()) + " EDGE lines");
  RobotShare s;
  s.d = g.d;
  s.num_poses = 0;  // unknown until the assignment
  s.begin = static_cast<std::uint32_t>(begin);
  s.end = static_cast<std::uint32_t>(end);
  s.measurements = std::move(g.measurements);
  s.measurement_index.reserve(s.measurements.size());
  for (std::size_t k = 0; k < s.measurements.size(); ++k) {
    Measurement& m = s.measurements[k];
    m.i = global[m.i];
    m.j = global[m.j];
    s.measurement_index.push_back(have_index ? index[k]
                                             : (static_cast<std::uint64_t>(robot) << 40) + k);
  }
  if (g.has_initial()) s.initial.assign(g.initial.begin(), g.initial.begin() + (end - begin));
  std::sort(known.begin(), known.end());
  std::vector<std::uint64_t> held = s.measurement_index;
  std::sort(held.begin(), held.end());
  for (std::uint64_t e : known)
    if (!std::binary_search(held.begin(), held.end(), e))
      throw InputError(path, known_line,
                       "'# tessera-known-inliers' names measurement " + std::to_string(e) +
                           ", which is not one of this file's EDGE lines");
  s.known_inlier_index = std::move(known);
  return s;
}

void adopt_num_poses(RobotShare& share, std::size_t n, const std::string& source) {
  if (share.end > n)
    throw InputError(source, 0,
                     "this robot's poses end at " + std::to_string(share.end) +
                         " but the whole graph has " + std::to_string(n) + " poses");
  for (const Measurement& m : share.measurements)
    if (m.i >= n || m.j >= n)
      throw InputError(source, 0,
                       "measurement " + std::to_string(m.i) + "-" + std::to_string(m.j) +
                           " names a pose beyond the whole graph's " + std::to_string(n) +
                           " poses");
  share.num_poses = n;
}

}  // namespace tessera::agent
