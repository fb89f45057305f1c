#pragma once
// One checkpoint on disk, written so that a crash at any moment never leaves a file that is
// later loaded with wrong contents:
//   - the bytes go to a temporary file in the same folder (PATH.tmp.<pid>), which is flushed
//     to disk (fsync) and then renamed over PATH (atomic on POSIX file systems); the folder
//     is fsynced too so the rename itself survives a power cut;
//   - the file starts with a header: magic "TSRCKPT\0", format version, payload length and a
//     64-bit FNV-1a checksum of the payload. A torn, truncated or corrupted file fails these
//     checks and is reported, never loaded.
// Leftover temporaries of a writer that died are never read (only PATH is), and the next
// write of the same PATH removes them.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tessera {

/// A checkpoint that cannot be used; what() names the file and the problem.
class CheckpointError : public std::runtime_error {
 public:
  explicit CheckpointError(const std::string& what) : std::runtime_error(what) {}
};

// 2: snapshots carry the neighbours' V (Vn); 3: the run options carry the coarse schedule.
constexpr std::uint32_t kCheckpointFormatVersion = 3;

/// Writes `payload` to `path` atomically (see above). Throws CheckpointError naming the file
/// and the failing system call.
void write_checkpoint_file(const std::string& path, const std::string& payload);

/// The payload of a valid checkpoint file. Throws CheckpointError naming the file when it is
/// missing, unreadable, too short, has a wrong magic/version, a length that does not match the
/// file size, or a checksum mismatch.
std::string read_checkpoint_file(const std::string& path);

/// 64-bit FNV-1a of `bytes` (the checkpoint checksum).
std::uint64_t checkpoint_checksum(const std::string& bytes);

}  // namespace tessera
