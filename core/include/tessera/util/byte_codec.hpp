#pragma once
// A tiny binary encoding for checkpoints: fixed-width little-endian-as-stored values (the file
// is read back by the same build on the same machine class; the checkpoint header's version
// guards format changes), length-prefixed strings and arrays, and Eigen matrices with their
// shape. The reader never reads past the end: a short or inconsistent buffer throws
// CodecError naming what was being read, so a damaged checkpoint is an error, not a crash.

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace tessera {

/// A buffer that does not hold what was to be read from it (short, inconsistent, trailing bytes).
class CodecError : public std::runtime_error {
 public:
  explicit CodecError(const std::string& what) : std::runtime_error(what) {}
};

/// Appends values to a byte string; each ByteReader call of the same name and order reads
/// back exactly what the writer call wrote (doubles bit-identical, NUL bytes kept).
class ByteWriter {
 public:
  void u32(std::uint32_t v) { raw(&v, sizeof v); }
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void i64(std::int64_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void boolean(bool v) { u32(v ? 1u : 0u); }
  void string(const std::string& s);
  void doubles(const std::vector<double>& v);
  void u32s(const std::vector<std::uint32_t>& v);
  void u64s(const std::vector<std::uint64_t>& v);
  void ints(const std::vector<int>& v);
  void matrix(const Eigen::MatrixXd& m);
  /// Everything written so far.
  const std::string& bytes() const { return bytes_; }

 private:
  void raw(const void* p, std::size_t n) { bytes_.append(static_cast<const char*>(p), n); }
  std::string bytes_;
};

class ByteReader {
 public:
  /// `what` names the buffer in errors (e.g. the checkpoint file).
  ByteReader(const std::string& bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}
  /// Each reads the next value of its kind. `field` names it in the CodecError thrown when
  /// the bytes left are too few, a count exceeds them, or a boolean is not 0 or 1.
  std::uint32_t u32(const char* field);
  std::uint64_t u64(const char* field);
  std::int64_t i64(const char* field);
  double f64(const char* field);
  bool boolean(const char* field);
  std::string string(const char* field);
  std::vector<double> doubles(const char* field);
  std::vector<std::uint32_t> u32s(const char* field);
  std::vector<std::uint64_t> u64s(const char* field);
  std::vector<int> ints(const char* field);
  Eigen::MatrixXd matrix(const char* field);
  /// True once every byte was read.
  bool at_end() const { return pos_ == bytes_.size(); }
  /// Throws CodecError unless every byte was read (trailing garbage means a format mismatch).
  void expect_end() const;

 private:
  void raw(void* p, std::size_t n, const char* field);
  std::size_t count(std::size_t element_size, const char* field);
  const std::string& bytes_;
  std::string what_;
  std::size_t pos_ = 0;
};

}  // namespace tessera
