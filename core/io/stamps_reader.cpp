#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <tessera/io/stamps_reader.hpp>
#include <tessera/io/text_file_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"
#include "io/number_token.hpp"

namespace tessera {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tok;
  for (std::string t; in >> t;) tok.push_back(t);
  return tok;
}

}  // namespace

std::vector<double> read_stamps_file(const std::string& path, const PoseGraph& graph,
                                     const PoseKeys& keys) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the stamps file");
  const std::size_t n = graph.num_poses;
  std::vector<double> stamps(n, 0.0);
  std::vector<std::size_t> line_of(n, 0);  // line that gave pose k its stamp
  std::size_t line = 0, rows = 0, columns = 0;
  std::string text;
  while (std::getline(in, text)) {
    ++line;
    const auto tok = split(text);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (columns == 0) {
      columns = tok.size();
      if (columns != 2 && columns != 8)
        throw InputError(path, line,
                         "a stamps line has 2 values (id stamp) or 8 (TUM: stamp tx ty tz qx qy "
                         "qz qw), found " +
                             std::to_string(tok.size()));
    } else if (tok.size() != columns) {
      throw InputError(path, line,
                       "expected " + std::to_string(columns) +
                           " values like the first line, found " + std::to_string(tok.size()));
    }
    double stamp = 0;
    const std::string& s = columns == 2 ? tok[1] : tok[0];
    if (!parse_number(s, stamp) || !std::isfinite(stamp))
      throw InputError(path, line, "stamp '" + s + "' is not a finite number");
    std::size_t k = rows;
    if (columns == 2) {
      std::uint64_t id = 0;
      auto [p, ec] = std::from_chars(tok[0].data(), tok[0].data() + tok[0].size(), id);
      if (ec != std::errc() || p != tok[0].data() + tok[0].size())
        throw InputError(path, line, "pose id '" + tok[0] + "' is not a non-negative integer");
      std::optional<std::size_t> found = keys.find(id);
      if (keys.ids.empty() && id < n) found = static_cast<std::size_t>(id);
      if (!found)
        throw InputError(path, line, "pose id " + tok[0] + " is not a pose of " + graph.source);
      k = *found;
    } else if (k >= n) {
      throw InputError(path, line,
                       "more stamp lines than the " + std::to_string(n) + " poses of " +
                           graph.source + " (TUM stamps are matched by order)");
    }
    if (line_of[k] != 0)
      throw InputError(path, line,
                       "pose id " + std::to_string(keys.id(k)) + " already has a stamp (line " +
                           std::to_string(line_of[k]) + ")");
    stamps[k] = stamp;
    line_of[k] = line;
    ++rows;
  }
  if (rows != n) {
    std::size_t missing = 0;
    while (missing < n && line_of[missing] != 0) ++missing;
    throw InputError(path, 0,
                     std::to_string(rows) + " stamps for the " + std::to_string(n) + " poses of " +
                         graph.source + " (first pose without one: id " +
                         std::to_string(keys.id(missing)) + ")");
  }
  return stamps;
}

void write_stamps_file(const PoseKeys& keys, std::size_t num_poses, const std::string& path) {
  TextFileWriter file(path);
  std::string& out = file.buffer();
  out += "# id stamp (s)\n";
  for (std::size_t k = 0; k < num_poses && k < keys.stamps.size(); ++k) {
    append_integer(out, keys.id(k));
    out += ' ';
    append_number(out, keys.stamps[k]);
    out += '\n';
    file.maybe_flush();
  }
  file.close();
}

}  // namespace tessera
