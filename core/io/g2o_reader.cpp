#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/information_weights.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "io/g2o_graph_checks.hpp"
#include "io/number_token.hpp"
#include "io/rotation_text.hpp"
#include "io/toro_records.hpp"

namespace tessera {
namespace {

// The longest record (EDGE_SE3:QUAT) has 31 tokens; longer lines are only counted.
constexpr std::size_t kMaxTokens = 32;
// Quaternions shorter than this cannot be turned into a rotation meaningfully.
constexpr double kMinQuaternionNorm = 1e-6;
// Larger inputs are refused rather than read forever (e.g. /dev/zero); the biggest public
// benchmark graphs are a few tens of MB.
constexpr std::size_t kMaxInputBytes = std::size_t{2} << 30;

struct RecordSpec {
  const char* tag;
  int d;
  bool edge;
  std::size_t values;  // tokens after the tag
  const char* layout;
  bool toro;  // TORO dialect (toro_records.hpp converts its values)
};

const RecordSpec kSpecs[] = {
    {"VERTEX_SE2", 2, false, 4, "id x y theta", false},
    {"EDGE_SE2", 2, true, 11, "i j dx dy dtheta and 6 information values", false},
    {"VERTEX_SE3:QUAT", 3, false, 8, "id x y z qx qy qz qw", false},
    {"EDGE_SE3:QUAT", 3, true, 30, "i j x y z qx qy qz qw and 21 information values", false},
    {"VERTEX2", 2, false, 4, "id x y theta", true},
    {"EDGE2", 2, true, 11, "i j dx dy dtheta Ixx Ixy Iyy Itt Ixt Iyt", true},
    {"VERTEX3", 3, false, 7, "id x y z roll pitch yaw", true},
    {"EDGE3", 3, true, 29, "i j x y z roll pitch yaw and 21 information values", true},
};

// Name of value k (0-based, after the tag) of a record, for error messages.
std::string field_name(const RecordSpec& spec, std::size_t k) {
  if (spec.toro) return "value " + std::to_string(k + 1);
  static const char* const kVertex2[] = {"id", "x", "y", "theta"};
  static const char* const kVertex3[] = {"id", "x", "y", "z", "qx", "qy", "qz", "qw"};
  static const char* const kEdge2[] = {"i", "j", "dx", "dy", "dtheta"};
  static const char* const kEdge3[] = {"i", "j", "x", "y", "z", "qx", "qy", "qz", "qw"};
  if (!spec.edge) return spec.d == 2 ? kVertex2[k] : kVertex3[k];
  const std::size_t head = spec.d == 2 ? 5 : 9;
  if (k < head) return spec.d == 2 ? kEdge2[k] : kEdge3[k];
  // Information entry number k - head of the row-major upper triangle.
  int size = spec.d == 2 ? 3 : 6, idx = static_cast<int>(k - head), r = 0;
  while (idx >= size - r) idx -= size - r++;
  return "I" + std::to_string(r + 1) + std::to_string(r + 1 + idx);
}

// Field separators (a table: the tokenizer looks at every byte of the file).
struct BlankTable {
  bool blank[256] = {};
  constexpr BlankTable() {
    for (unsigned char c : {' ', '\t', '\r', '\v', '\f'}) blank[c] = true;
  }
};
constexpr BlankTable kBlanks;
inline bool is_blank(char c) {
  return kBlanks.blank[static_cast<unsigned char>(c)];
}

// A number in a message (not for reading back).
std::string number_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

class Parser {
 public:
  Parser(const std::string& name, const G2oReadOptions& options, std::size_t size_hint)
      : name_(name), options_(options) {
    options_.validate();
    result_.graph.source = name_;
    // An EDGE line has at least 30 bytes: reserving for that many measurements avoids moving
    // them while the vector grows (untouched capacity costs no memory pages).
    const std::size_t max_edges = std::min<std::size_t>(size_hint / 30 + 1, 1 << 22);
    result_.graph.measurements.reserve(max_edges);
    edge_lines_.reserve(max_edges);
    const std::size_t max_vertices = std::min<std::size_t>(size_hint / 18 + 1, 1 << 22);
    result_.graph.initial.reserve(max_vertices);  // (a VERTEX line has at least 18 bytes)
    vertex_lines_.reserve(max_vertices);
  }

  /// Parses whole lines [p, end): each ends with '\n', except a last line of the input.
  void feed(const char* p, const char* end) {
    if (!bom_checked_ && p < end) {  // (the first non-empty call holds a whole line)
      bom_checked_ = true;
      // A UTF-8 byte-order mark from some editors is not part of the first tag.
      if (end - p >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3;
    }
    while (p < end) {
      const auto* nl = static_cast<const char*>(std::memchr(p, '\n', end - p));
      const char* eol = nl ? nl : end;
      ++line_;
      parse_line(p, eol);
      p = nl ? nl + 1 : end;
    }
  }

  G2oReadResult finish() {
    stats().lines = line_;
    stats().format = toro_ ? "toro" : "g2o";
    check_g2o_graph(name_, options_, line_, edge_lines_, loose_, fixes_, result_);
    return std::move(result_);
  }

 private:
  G2oReadStats& stats() { return result_.stats; }

  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw InputError(name_, line, what);
  }

  void parse_line(const char* p, const char* eol) {
    count_ = 0;
    while (p < eol) {
      while (p < eol && is_blank(*p)) ++p;
      if (p == eol) break;
      const char* s = p;
      while (p < eol && !is_blank(*p)) ++p;
      if (count_ < kMaxTokens) tok_[count_] = std::string_view(s, p - s);
      ++count_;
    }
    if (count_ == 0) {
      ++stats().blank_lines;
      return;
    }
    const std::string_view tag = tok_[0];
    if (tag[0] == '#') {
      ++stats().comment_lines;
      return;
    }
    if (tag == "FIX") {
      // The first fixed pose chooses the gauge of the output (g2o_graph_checks.cpp).
      if (count_ < 2) fail(line_, "FIX needs at least one pose id");
      for (std::size_t k = 1; k < count_ && k < kMaxTokens; ++k) {
        const std::uint64_t id = parse_id(tok_[k], "FIX pose id");
        if (fixes_.empty()) fixes_.push_back({id, static_cast<std::uint32_t>(line_), Pose{}});
      }
      if (count_ > kMaxTokens) fail(line_, "FIX line has too many fields");
      ++stats().fix_lines;
      return;
    }
    const RecordSpec* spec = nullptr;
    for (const auto& s : kSpecs)
      if (tag == s.tag) spec = &s;
    if (!spec)
      fail(line_, "unknown tag " + quoted_token(tag) +
                      " (not a g2o file: VERTEX_SE2, EDGE_SE2, VERTEX_SE3:QUAT, EDGE_SE3:QUAT, "
                      "FIX; nor a TORO file: VERTEX2, EDGE2, VERTEX3, EDGE3)");
    if (count_ - 1 != spec->values)
      fail(line_, std::string(spec->tag) + " needs " + std::to_string(spec->values) + " values (" +
                      spec->layout + "), found " + std::to_string(count_ - 1));
    if (d_ == 0) {
      toro_ = spec->toro;
      d_ = spec->d;
      d_line_ = line_;
      d_tag_ = spec->tag;
      result_.graph.d = d_;
    } else if (d_ != spec->d) {
      fail(line_, "mixed 2D and 3D records: " + std::string(spec->tag) + " here, but line " +
                      std::to_string(d_line_) + " has " + d_tag_);
    } else if (toro_ != spec->toro) {
      fail(line_, "mixed g2o and TORO records: " + std::string(spec->tag) + " here, but line " +
                      std::to_string(d_line_) + " has " + d_tag_);
    }
    if (spec->edge)
      parse_edge(*spec);
    else
      parse_vertex(*spec);
  }

  std::uint64_t parse_id(std::string_view s, const std::string& role) {
    if (!s.empty() && s[0] == '-') {
      double x;
      if (parse_number(s, x)) fail(line_, role + " " + quoted_token(s) + " is negative");
    }
    std::uint64_t id = 0;
    auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), id);
    if (ptr != s.data() + s.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
      fail(line_, role + " " + quoted_token(s) + " is not a non-negative integer");
    if (ec == std::errc::result_out_of_range)
      fail(line_, role + " " + quoted_token(s) + " is too large (at most 2^64 - 1)");
    if (options_.keys == KeyScheme::kGtsam && !is_gtsam_key(id))
      fail(line_, role + " " + quoted_token(s) +
                      " is not a GTSAM key (--keys gtsam): its top byte " +
                      std::to_string(id >> 56) + " is not a robot letter A-Z or a-z");
    return id;
  }

  // Values first..spec.values-1 (after the tag) as finite doubles into vals_.
  void parse_values(const RecordSpec& spec, std::size_t first) {
    for (std::size_t k = first; k < spec.values; ++k) {
      const std::string_view s = tok_[k + 1];
      double x;
      if (!parse_number(s, x))
        fail(line_, std::string(spec.tag) + " " + field_name(spec, k) + " (column " +
                        std::to_string(k + 2) + "): " + quoted_token(s) + " is not a number");
      if (!std::isfinite(x))
        fail(line_, std::string(spec.tag) + " " + field_name(spec, k) + " (column " +
                        std::to_string(k + 2) + "): " + quoted_token(s) + " is not finite");
      vals_[k] = x;
    }
  }

  double quaternion_norm(const double* q) {
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm >= kMinQuaternionNorm))
      fail(line_, "zero quaternion (norm " + number_text(norm) + "): not a rotation");
    if (!std::isfinite(norm)) fail(line_, "quaternion too large to normalise");
    return norm;
  }

  // Vertices normally come as ids 0, 1, 2, ...: their poses go straight into graph.initial
  // and only their line numbers are kept. The first vertex out of that order moves them all
  // to a list that is sorted and checked at the end (so any order is still accepted).
  void parse_vertex(const RecordSpec& spec) {
    const std::uint64_t id = parse_id(tok_[1], "pose id");
    parse_values(spec, 1);
    Pose pose;
    if (spec.toro && spec.d == 3) {
      pose.R = rotation_from_roll_pitch_yaw(vals_[4], vals_[5], vals_[6]);
      pose.t.resize(3);
      pose.t << vals_[1], vals_[2], vals_[3];
    } else if (spec.d == 2) {
      pose.R = planar_rotation(vals_[3]);
      pose.t.resize(2);
      pose.t << vals_[1], vals_[2];
    } else {
      // The initial guess must lie on SE(3), so vertex quaternions are always normalised.
      double* q = &vals_[4];
      const double norm = quaternion_norm(q);
      pose.R = rotation_from_quaternion(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
      pose.t.resize(3);
      pose.t << vals_[1], vals_[2], vals_[3];
    }
    auto& initial = result_.graph.initial;
    const auto line = static_cast<std::uint32_t>(line_);
    if (loose_.empty() && id == initial.size()) {
      initial.push_back(std::move(pose));
      vertex_lines_.push_back(line);
    } else {
      if (loose_.empty()) {
        loose_.reserve(initial.size() + 1);
        for (std::size_t k = 0; k < initial.size(); ++k)
          loose_.push_back({k, vertex_lines_[k], std::move(initial[k])});
        initial.clear();
      }
      loose_.push_back({id, line, std::move(pose)});
    }
    ++stats().vertex_lines;
  }

  void parse_edge(const RecordSpec& spec) {
    const std::uint64_t i = parse_id(tok_[1], "pose id i");
    const std::uint64_t j = parse_id(tok_[2], "pose id j");
    if (i == j) fail(line_, "self-loop: edge from pose " + std::to_string(i) + " to itself");
    parse_values(spec, 2);
    Measurement m;
    m.i = static_cast<std::size_t>(i);
    m.j = static_cast<std::size_t>(j);
    const double* info;
    IsotropicWeights w;
    if (spec.toro) {
      if (spec.d == 2) {
        m.R = planar_rotation(vals_[4]);
        m.t.resize(2);
        m.t << vals_[2], vals_[3];
        toro_information_2d(&vals_[5], info_.data());
        info = info_.data();
        w = isotropic_weights_2d(info);
      } else {
        m.R = rotation_from_roll_pitch_yaw(vals_[5], vals_[6], vals_[7]);
        m.t.resize(3);
        m.t << vals_[2], vals_[3], vals_[4];
        toro_information_3d(&vals_[8], info_.data());
        info = info_.data();
        w = isotropic_weights_3d(info);
      }
    } else if (spec.d == 2) {
      m.R = planar_rotation(vals_[4]);
      m.t.resize(2);
      m.t << vals_[2], vals_[3];
      info = &vals_[5];
      w = isotropic_weights_2d(info);
    } else {
      m.t.resize(3);
      m.t << vals_[2], vals_[3], vals_[4];
      double* q = &vals_[5];
      const double norm = quaternion_norm(q);
      stats().max_quaternion_norm_error =
          std::max(stats().max_quaternion_norm_error, std::abs(norm - 1.0));
      if (options_.normalize_quaternions)
        for (int k = 0; k < 4; ++k) q[k] /= norm;
      m.R = rotation_from_quaternion(q[0], q[1], q[2], q[3]);
      info = &vals_[9];
      w = isotropic_weights_3d(info);
    }
    if (!upper_triangle_is_positive_definite(info, spec.d == 2 ? 3 : 6)) {
      if (stats().non_pd_information++ == 0) stats().first_non_pd_line = line_;
    }
    if (!(std::isfinite(w.tau) && w.tau > 0))
      fail(line_, "the information matrix gives translation weight tau = " + number_text(w.tau) +
                      " (must be finite and > 0): its translation block is singular or not "
                      "positive definite");
    if (!(std::isfinite(w.kappa) && w.kappa > 0))
      fail(line_, "the information matrix gives rotation weight kappa = " + number_text(w.kappa) +
                      " (must be finite and > 0): its rotation " +
                      (spec.d == 2 ? "entry I33 is not positive"
                                   : "block is singular or not positive definite"));
    m.kappa = w.kappa;
    m.tau = w.tau;
    result_.graph.measurements.push_back(std::move(m));
    edge_lines_.push_back(static_cast<std::uint32_t>(line_));
    ++stats().edge_lines;
  }

  const std::string& name_;
  const G2oReadOptions& options_;
  G2oReadResult result_;
  std::size_t line_ = 0;
  bool bom_checked_ = false;
  std::array<std::string_view, kMaxTokens> tok_{};
  std::size_t count_ = 0;
  std::array<double, 30> vals_{};
  std::array<double, 21> info_{};  // a TORO information matrix in g2o's order
  int d_ = 0;
  bool toro_ = false;
  std::vector<G2oLooseVertex> fixes_;  // the first FIX id (pose unused) and its line
  std::size_t d_line_ = 0;
  std::string d_tag_;
  std::vector<std::uint32_t> vertex_lines_;  // line of graph.initial[k] while in order
  std::vector<G2oLooseVertex> loose_;        // all vertices once one came out of order
  std::vector<std::uint32_t> edge_lines_;    // line of each measurement (inputs < 2^32 lines)
};

// Parses what `read_some(buffer, capacity)` delivers (it returns the bytes read, 0 at the
// end) through one reused buffer, whole lines at a time, so the input never sits in memory
// as a whole: fresh memory pages are expensive on small VMs, and a few MB of file would
// cost more in page faults than the parsing itself.
template <class ReadSome>
G2oReadResult parse_chunks(ReadSome&& read_some, std::size_t size_hint, const std::string& name,
                           const G2oReadOptions& options) {
  Parser parser(name, options, size_hint);
  // Not zero-filled: only the pages the input reaches are ever touched.
  std::size_t capacity = options.read_chunk_bytes;
  std::unique_ptr<char[]> buffer(new char[capacity]);
  std::size_t have = 0;  // bytes of an unfinished line kept at the start of the buffer
  std::size_t total = 0;
  for (;;) {
    if (have == capacity) {  // a line longer than the buffer
      std::unique_ptr<char[]> bigger(new char[2 * capacity]);
      std::memcpy(bigger.get(), buffer.get(), have);
      buffer = std::move(bigger);
      capacity *= 2;
    }
    const std::size_t got = read_some(buffer.get() + have, capacity - have);
    total += got;
    if (total > kMaxInputBytes) throw InputError(name, 0, "input too large (over 2 GiB)");
    const char* begin = buffer.get();
    const char* end = begin + have + got;
    if (got == 0) {  // the end: the rest is the last line
      parser.feed(begin, end);
      break;
    }
    const char* stop = end;
    while (stop > begin && stop[-1] != '\n') --stop;
    parser.feed(begin, stop);
    have = static_cast<std::size_t>(end - stop);
    std::memmove(buffer.get(), stop, have);
  }
  return parser.finish();
}

}  // namespace

void G2oReadOptions::validate() const {
  if (read_chunk_bytes < 1 || read_chunk_bytes > (std::size_t{1} << 30))
    throw InputError("G2oReadOptions.read_chunk_bytes must be in 1..2^30, got " +
                     std::to_string(read_chunk_bytes));
}

G2oReadResult read_g2o_text(std::string_view text, const std::string& name,
                            const G2oReadOptions& options) {
  Parser parser(name, options, text.size());
  parser.feed(text.data(), text.data() + text.size());
  return parser.finish();
}

G2oReadResult read_g2o_stream(std::istream& in, const std::string& name,
                              const G2oReadOptions& options) {
  if (!in) throw InputError(name, 0, "cannot read the input stream");
  auto read_some = [&](char* buf, std::size_t cap) {
    in.read(buf, static_cast<std::streamsize>(cap));
    if (in.bad()) throw InputError(name, 0, "error while reading the input stream");
    return static_cast<std::size_t>(in.gcount());
  };
  return parse_chunks(read_some, 0, name, options);
}

G2oReadResult read_g2o_file(const std::string& path, const G2oReadOptions& options) {
  options.validate();
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, 0, std::string("cannot open the file: ") + std::strerror(errno));
  // Closes the file on every path out, errors included.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, &std::fclose);
  std::size_t size_hint = 0;
  struct stat st {};
  if (fstat(fileno(f), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw InputError(path, 0, "cannot read the file: it is a directory");
    if (S_ISREG(st.st_mode) && st.st_size > 0) size_hint = static_cast<std::size_t>(st.st_size);
  }
  auto read_some = [&](char* buf, std::size_t cap) {
    const std::size_t got = std::fread(buf, 1, cap, f);
    if (got < cap && std::ferror(f))
      throw InputError(path, 0, std::string("cannot read the file: ") + std::strerror(errno));
    return got;
  };
  return parse_chunks(read_some, size_hint, path, options);
}

PoseGraph read_g2o(const std::string& path, const G2oReadOptions& options) {
  return read_g2o_file(path, options).graph;
}

PoseGraph read_g2o(std::istream& in, const std::string& name, const G2oReadOptions& options) {
  return read_g2o_stream(in, name, options).graph;
}

}  // namespace tessera
