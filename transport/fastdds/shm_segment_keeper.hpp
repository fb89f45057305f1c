#pragma once
// Keeps a deleted participant's shared-memory data segment readable for the peers that read its
// last messages late.
//
// Why: a Fast DDS 2.9.1 shared-memory listener opens a sender's data segment (/dev/shm/
// fastrtps_<hex>) by name when it reads a message of that sender and has no copy of it open (the
// first message from that sender, or any message after the listener's watchdog let its copy go
// because the sender died). If the sender deleted its participant meanwhile (which removes the
// name), the open fails, the message stays at the head of the port's queue and the listener
// retries it forever: that port hears nothing more and the receive thread spins
// (shm_receive_watch.hpp; fixed upstream after 2.9: eProsima/Fast-DDS pull 3992). A deleted
// participant's last messages are discovery messages to every participant of the domain (with
// discovery over shared memory, --transport shm: other runs' participants too), and any peer
// may read a message late on a loaded host.
//
// What: just before the participant is deleted, keep() makes a hard link to each data segment
// of this process (a segment it maps and whose lock file it holds); just after, restore() gives
// each segment whose name Fast DDS removed its name back and leaves a marker
// (tessera_kept_<hex>). The memory and its messages stay as they were, so a listener that reads
// a message of ours late, or is already retrying one, opens the segment and goes on. A restored
// name goes again when a Tessera process deletes its participant at least kKeptSegmentLifeS
// after it was restored (sweep_kept_segments(), called by every deletion), or when the
// `tessera launch` whose process restored it ends (its processes' ones, at once); peers that
// opened the segment also remove the name once their watchdog sees the owner gone (Fast DDS does
// that for every dead sender, 5 s after its last check). No Fast DDS types: compiled into
// tessera_session_options, which both the transport and launch/ link.

#include <string>
#include <utility>
#include <vector>

namespace tessera::transport {

/// How long a restored segment name stays before sweep_kept_segments() removes it (seconds).
inline constexpr double kKeptSegmentLifeS = 10.0;

class ShmSegmentKeeper {
 public:
  explicit ShmSegmentKeeper(std::string dir = "/dev/shm");
  /// Before deleting a participant: hard links to this process's own data segments.
  void keep();
  /// After deleting it: the names Fast DDS removed come back (returned); the links go.
  std::vector<std::string> restore();
  ~ShmSegmentKeeper();  ///< Removes links restore() did not use.

 private:
  std::string dir_;
  unsigned long id_;               // this keeper's number in the process (its links' names)
  std::vector<std::string> kept_;  // segment names (fastrtps_<hex>) linked by keep()
};

/// The data segments (fastrtps_<hex>) this process maps and whose lock file it holds.
std::vector<std::string> own_shm_segments(const std::string& dir = "/dev/shm");

/// Removes the restored segments (with their markers) whose owner's lock is not held and that
/// were restored at least `life_s` seconds ago or by one of the processes `owners`. Returns how
/// many segments it removed.
int sweep_kept_segments(const std::string& dir = "/dev/shm", double life_s = kKeptSegmentLifeS,
                        const std::vector<int>& owners = {});

}  // namespace tessera::transport
