#include <cerrno>
#include <cstring>
#include <tessera/io/text_file_writer.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {
constexpr std::size_t kFlushBytes = 1 << 20;
}  // namespace

TextFileWriter::TextFileWriter(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_)
    throw InputError(path, 0, std::string("cannot open for writing: ") + std::strerror(errno));
  buffer_.reserve(kFlushBytes + 4096);
}

TextFileWriter::~TextFileWriter() {
  if (file_) std::fclose(file_);  // only reached when close() was skipped by an exception
}

void TextFileWriter::maybe_flush() {
  if (buffer_.size() >= kFlushBytes) flush();
}

void TextFileWriter::flush() {
  if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
    throw InputError(path_, 0, std::string("write failed: ") + std::strerror(errno));
  buffer_.clear();
}

void TextFileWriter::close() {
  flush();
  std::FILE* f = file_;
  file_ = nullptr;
  if (std::fclose(f) != 0)
    throw InputError(path_, 0, std::string("write failed: ") + std::strerror(errno));
}

}  // namespace tessera
