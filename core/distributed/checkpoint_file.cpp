#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <tessera/distributed/checkpoint_file.hpp>
#include <tessera/util/byte_codec.hpp>
#include <vector>

namespace tessera {
namespace {

constexpr char kMagic[8] = {'T', 'S', 'R', 'C', 'K', 'P', 'T', '\0'};
constexpr std::size_t kHeaderSize = 8 + 4 + 8 + 8;  // magic, version, length, checksum

std::string sys_error(const std::string& path, const char* what) {
  return "checkpoint " + path + ": " + what + " failed: " + std::strerror(errno);
}

std::string folder_of(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string base_of(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void write_all(int fd, const char* p, std::size_t n, const std::string& path) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw CheckpointError(sys_error(path, "write"));
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}

// Temporaries of writers that died (PATH.tmp.<pid> of a process that no longer exists, or of
// this process from an earlier interrupted write) are garbage: remove them.
void remove_stale_temporaries(const std::string& path) {
  const std::string folder = folder_of(path), prefix = base_of(path) + ".tmp.";
  DIR* dir = ::opendir(folder.c_str());
  if (!dir) return;
  std::vector<std::string> stale;
  while (const dirent* e = ::readdir(dir)) {
    const std::string name = e->d_name;
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) != 0)
      stale.push_back(folder + "/" + name);
  }
  ::closedir(dir);
  for (const auto& s : stale) ::unlink(s.c_str());
}

}  // namespace

std::uint64_t checkpoint_checksum(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

void write_checkpoint_file(const std::string& path, const std::string& payload) {
  remove_stale_temporaries(path);
  ByteWriter fields;
  fields.u32(kCheckpointFormatVersion);
  fields.u64(payload.size());
  fields.u64(checkpoint_checksum(payload));
  const std::string header = std::string(kMagic, sizeof kMagic) + fields.bytes();

  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw CheckpointError(sys_error(tmp, "open"));
  try {
    write_all(fd, header.data(), header.size(), tmp);
    write_all(fd, payload.data(), payload.size(), tmp);
    if (::fsync(fd) != 0) throw CheckpointError(sys_error(tmp, "fsync"));
  } catch (...) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    ::unlink(tmp.c_str());
    throw CheckpointError(sys_error(tmp, "close"));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string err = sys_error(path, "rename");
    ::unlink(tmp.c_str());
    throw CheckpointError(err);
  }
  const std::string folder = folder_of(path);
  const int dfd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {  // best effort: some file systems refuse fsync on folders
    ::fsync(dfd);
    ::close(dfd);
  }
}

std::string read_checkpoint_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CheckpointError("checkpoint " + path + ": cannot open: " + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  auto bad = [&](const std::string& why) {
    return CheckpointError("checkpoint " + path + " is not usable: " + why);
  };
  if (bytes.size() < kHeaderSize)
    throw bad("only " + std::to_string(bytes.size()) +
              " bytes, shorter than the header (torn write?)");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw bad("not a Tessera checkpoint (bad magic)");
  // The size check above guarantees these reads succeed.
  const std::string fields = bytes.substr(sizeof kMagic, kHeaderSize - sizeof kMagic);
  ByteReader header(fields, path);
  const std::uint32_t version = header.u32("format version");
  const std::uint64_t length = header.u64("payload length"), sum = header.u64("checksum");
  if (version != kCheckpointFormatVersion)
    throw bad("format version " + std::to_string(version) + ", this build reads version " +
              std::to_string(kCheckpointFormatVersion));
  if (length != bytes.size() - kHeaderSize)
    throw bad("header says " + std::to_string(length) + " payload bytes, the file has " +
              std::to_string(bytes.size() - kHeaderSize) + " (truncated or torn)");
  std::string payload = bytes.substr(kHeaderSize);
  if (checkpoint_checksum(payload) != sum) throw bad("checksum mismatch (corrupted)");
  return payload;
}

}  // namespace tessera
