#pragma once
// A buffered text file for the writers: collects lines in memory and flushes them in large
// chunks, so multi-gigabyte graph files are written at disk speed. Every failure (cannot
// open, disk full) is an InputError naming the path.

#include <cstdio>
#include <string>

namespace tessera {

class TextFileWriter {
 public:
  /// Opens (truncates) `path` for writing; throws InputError when it cannot.
  explicit TextFileWriter(const std::string& path);
  ~TextFileWriter();
  TextFileWriter(const TextFileWriter&) = delete;
  TextFileWriter& operator=(const TextFileWriter&) = delete;

  /// The pending text; append to it freely, then call maybe_flush() once per line.
  std::string& buffer() { return buffer_; }
  /// Writes the buffer out when it has grown large.
  void maybe_flush();
  /// Writes everything and closes the file; throws InputError if any write failed.
  void close();

 private:
  void flush();

  std::string path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
};

}  // namespace tessera
