#include <cstring>
#include <tessera/util/byte_codec.hpp>

namespace tessera {

void ByteWriter::string(const std::string& s) {
  u64(s.size());
  raw(s.data(), s.size());
}

void ByteWriter::doubles(const std::vector<double>& v) {
  u64(v.size());
  raw(v.data(), v.size() * sizeof(double));
}

void ByteWriter::u32s(const std::vector<std::uint32_t>& v) {
  u64(v.size());
  raw(v.data(), v.size() * sizeof(std::uint32_t));
}

void ByteWriter::u64s(const std::vector<std::uint64_t>& v) {
  u64(v.size());
  raw(v.data(), v.size() * sizeof(std::uint64_t));
}

void ByteWriter::ints(const std::vector<int>& v) {
  u64(v.size());
  for (int x : v) i64(x);
}

void ByteWriter::matrix(const Eigen::MatrixXd& m) {
  u64(static_cast<std::uint64_t>(m.rows()));
  u64(static_cast<std::uint64_t>(m.cols()));
  raw(m.data(), static_cast<std::size_t>(m.size()) * sizeof(double));
}

void ByteReader::raw(void* p, std::size_t n, const char* field) {
  if (n > bytes_.size() - pos_)
    throw CodecError(what_ + ": truncated while reading " + field + " (needs " + std::to_string(n) +
                     " bytes at offset " + std::to_string(pos_) + ", " +
                     std::to_string(bytes_.size() - pos_) + " left)");
  if (n) std::memcpy(p, bytes_.data() + pos_, n);
  pos_ += n;
}

std::size_t ByteReader::count(std::size_t element_size, const char* field) {
  const std::uint64_t n = u64(field);
  // A count larger than the remaining bytes can hold is corruption, not a huge allocation.
  if (element_size && n > (bytes_.size() - pos_) / element_size)
    throw CodecError(what_ + ": " + field + " claims " + std::to_string(n) +
                     " elements, more than the " + std::to_string(bytes_.size() - pos_) +
                     " bytes left");
  return static_cast<std::size_t>(n);
}

std::uint32_t ByteReader::u32(const char* field) {
  std::uint32_t v;
  raw(&v, sizeof v, field);
  return v;
}
std::uint64_t ByteReader::u64(const char* field) {
  std::uint64_t v;
  raw(&v, sizeof v, field);
  return v;
}
std::int64_t ByteReader::i64(const char* field) {
  std::int64_t v;
  raw(&v, sizeof v, field);
  return v;
}
double ByteReader::f64(const char* field) {
  double v;
  raw(&v, sizeof v, field);
  return v;
}
bool ByteReader::boolean(const char* field) {
  const std::uint32_t v = u32(field);
  if (v > 1) throw CodecError(what_ + ": " + field + " is not a boolean");
  return v == 1;
}
std::string ByteReader::string(const char* field) {
  std::string s(count(1, field), '\0');
  raw(s.data(), s.size(), field);
  return s;
}
std::vector<double> ByteReader::doubles(const char* field) {
  std::vector<double> v(count(sizeof(double), field));
  raw(v.data(), v.size() * sizeof(double), field);
  return v;
}
std::vector<std::uint32_t> ByteReader::u32s(const char* field) {
  std::vector<std::uint32_t> v(count(sizeof(std::uint32_t), field));
  raw(v.data(), v.size() * sizeof(std::uint32_t), field);
  return v;
}
std::vector<std::uint64_t> ByteReader::u64s(const char* field) {
  std::vector<std::uint64_t> v(count(sizeof(std::uint64_t), field));
  raw(v.data(), v.size() * sizeof(std::uint64_t), field);
  return v;
}
std::vector<int> ByteReader::ints(const char* field) {
  std::vector<int> v(count(sizeof(std::int64_t), field));
  for (int& x : v) x = static_cast<int>(i64(field));
  return v;
}
Eigen::MatrixXd ByteReader::matrix(const char* field) {
  const std::uint64_t rows = u64(field), cols = u64(field);
  if (rows > 0 && cols > (bytes_.size() - pos_) / sizeof(double) / rows)
    throw CodecError(what_ + ": " + field + " claims a " + std::to_string(rows) + " x " +
                     std::to_string(cols) + " matrix, larger than the bytes left");
  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  raw(m.data(), static_cast<std::size_t>(m.size()) * sizeof(double), field);
  return m;
}

void ByteReader::expect_end() const {
  if (!at_end())
    throw CodecError(what_ + ": " + std::to_string(bytes_.size() - pos_) +
                     " unexpected bytes after the last field");
}

}  // namespace tessera
