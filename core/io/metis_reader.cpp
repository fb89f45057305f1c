#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <tessera/io/metis_reader.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>
#include <vector>

namespace tessera {
namespace {

// Splits a line into whitespace-separated tokens.
std::vector<std::string> tokens_of(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

// Parses a non-negative decimal integer; false when the token is anything else.
bool parse_count(const std::string& tok, unsigned long long* value) {
  if (tok.empty() || tok.size() > 19) return false;
  for (char c : tok)
    if (c < '0' || c > '9') return false;
  errno = 0;
  *value = std::strtoull(tok.c_str(), nullptr, 10);
  return errno == 0;
}

bool is_comment(const std::string& line) {
  auto p = line.find_first_not_of(" \t\r");
  return p != std::string::npos && line[p] == '%';
}

bool is_blank(const std::string& line) {
  return line.find_first_not_of(" \t\r") == std::string::npos;
}

}  // namespace

bool looks_like_metis(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (is_comment(line) || is_blank(line)) continue;
    auto toks = tokens_of(line);
    if (toks.size() < 2 || toks.size() > 4) return false;
    unsigned long long x;
    for (const auto& t : toks)
      if (!parse_count(t, &x)) return false;
    return true;
  }
  return false;
}

GraphStructure read_metis(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open file");
  std::string line;
  std::size_t lineno = 0;
  // Header.
  std::vector<std::string> head;
  std::size_t header_line = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (is_comment(line) || is_blank(line)) continue;
    head = tokens_of(line);
    header_line = lineno;
    break;
  }
  if (header_line == 0) throw InputError(path, 0, "empty file: no METIS header 'n m [fmt [ncon]]'");
  unsigned long long hv[4] = {0, 0, 0, 1};
  bool ok = head.size() >= 2 && head.size() <= 4;
  for (std::size_t k = 0; ok && k < head.size(); ++k) ok = parse_count(head[k], &hv[k]);
  if (!ok)
    throw InputError(path, header_line,
                     "bad METIS header '" + line +
                         "': expected 'n m [fmt [ncon]]' (non-negative "
                         "integers)");
  const std::size_t n = hv[0], m = hv[1];
  const unsigned long long fmt = head.size() >= 3 ? hv[2] : 0;
  if (fmt != 0 && fmt != 1 && fmt != 10 && fmt != 11)
    throw InputError(path, header_line,
                     "unsupported METIS fmt " + head[2] + " (supported: 0, 1, 10, 11)");
  if (hv[3] != 1)
    throw InputError(path, header_line, "only one vertex weight per vertex (ncon 1) is supported");
  if (n > 100000000ULL)
    throw InputError(path, header_line, "vertex count " + head[0] + " too large");
  const bool edge_weights = fmt % 10 == 1, vertex_weights = fmt >= 10;

  // Adjacency entries as (u, v, weight, line of u).
  std::vector<std::tuple<std::size_t, std::size_t, std::size_t>> entries;
  std::vector<std::size_t> line_of(n, 0);
  entries.reserve(2 * std::min<std::size_t>(m, 50000000));
  std::size_t v = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (is_comment(line)) continue;
    if (v == n) {
      if (is_blank(line)) continue;
      throw InputError(path, lineno,
                       "more vertex lines than the " + std::to_string(n) + " the header announces");
    }
    auto toks = tokens_of(line);
    line_of[v] = lineno;
    std::size_t k = 0;
    if (vertex_weights) {
      unsigned long long w;
      if (toks.empty() || !parse_count(toks[0], &w))
        throw InputError(path, lineno,
                         "vertex " + std::to_string(v + 1) + ": missing vertex weight");
      if (w != 1)
        throw InputError(path, lineno,
                         "vertex " + std::to_string(v + 1) + " has weight " + toks[0] +
                             ": only unit vertex weights are supported");
      k = 1;
    }
    const std::size_t stride = edge_weights ? 2 : 1;
    if ((toks.size() - k) % stride != 0)
      throw InputError(path, lineno,
                       "vertex " + std::to_string(v + 1) + ": neighbour without an edge weight");
    for (; k < toks.size(); k += stride) {
      unsigned long long u;
      if (!parse_count(toks[k], &u))
        throw InputError(path, lineno, "'" + toks[k] + "' is not a vertex id");
      if (u < 1 || u > n)
        throw InputError(path, lineno,
                         "vertex id " + toks[k] + " out of range 1.." + std::to_string(n));
      if (u - 1 == v)
        throw InputError(path, lineno, "self loop on vertex " + std::to_string(v + 1));
      unsigned long long w = 1;
      if (edge_weights && (!parse_count(toks[k + 1], &w) || w == 0))
        throw InputError(path, lineno,
                         "edge weight '" + toks[k + 1] + "' is not a positive integer");
      entries.emplace_back(v, static_cast<std::size_t>(u - 1), static_cast<std::size_t>(w));
    }
    ++v;
  }
  if (v < n)
    throw InputError(path, lineno,
                     "file ends after " + std::to_string(v) + " vertex lines; header announces " +
                         std::to_string(n));
  if (entries.size() != 2 * m)
    throw InputError(path, header_line,
                     "header announces " + std::to_string(m) + " edges (" + std::to_string(2 * m) +
                         " adjacency entries) but the vertex lines hold " +
                         std::to_string(entries.size()) + " entries");

  // Symmetry: the multiset of (min, max, weight) seen from the lower end must equal the one
  // seen from the upper end.
  std::vector<std::tuple<std::size_t, std::size_t, std::size_t>> lo, hi;
  lo.reserve(m);
  hi.reserve(m);
  for (const auto& [a, b, w] : entries)
    (a < b ? lo : hi).emplace_back(std::min(a, b), std::max(a, b), w);
  std::sort(lo.begin(), lo.end());
  std::sort(hi.begin(), hi.end());
  if (lo != hi) {
    // Name one offending pair: the first difference between the two sorted lists.
    std::size_t k = 0;
    while (k < lo.size() && k < hi.size() && lo[k] == hi[k]) ++k;
    auto bad = k < lo.size() && (k >= hi.size() || lo[k] < hi[k]) ? lo[k] : hi[k];
    const std::size_t a = std::get<0>(bad), b = std::get<1>(bad);
    const bool from_low = k < lo.size() && (k >= hi.size() || lo[k] < hi[k]);
    const std::size_t listed_by = from_low ? a : b, missing_in = from_low ? b : a;
    throw InputError(path, line_of[listed_by],
                     "asymmetric adjacency: vertex " + std::to_string(listed_by + 1) + " lists " +
                         std::to_string(missing_in + 1) + " (weight " +
                         std::to_string(std::get<2>(bad)) + ") but vertex " +
                         std::to_string(missing_in + 1) + " does not list it back the same way");
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::vector<std::size_t> weights;
  pairs.reserve(lo.size());
  weights.reserve(lo.size());
  for (const auto& [a, b, w] : lo) {
    pairs.emplace_back(a, b);
    weights.push_back(w);
  }
  return make_graph_structure(n, pairs, weights, path);
}

}  // namespace tessera
