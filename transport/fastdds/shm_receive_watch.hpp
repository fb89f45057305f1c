#pragma once
// Names a Fast DDS 2.9 shared-memory defect when a wait of this process times out.
//
// Why: a shared-memory listener of Fast DDS 2.9.1 reads a message's buffer from the sender's data
// segment (/dev/shm/fastrtps_<hex>), opened by name on the first message from that sender. If the
// sender deleted its participant (which removes the segment) before the listener read that first
// message, opening fails ("No such file or directory"), the message stays at the head of the
// port's queue, and the listener retries it forever: the participant never receives anything on
// that port again (and the listener thread spins). Fixed upstream after 2.9 (eProsima/Fast-DDS
// pull 3992, "ignore non-existing segment on pop"). It takes a participant that is just starting
// while another participant of the domain that has just discovered it is deleted: two runs on
// one domain, one ending while the other starts: `DdsRuntime.TwoConcurrentRunsOnOneDomainDoNot
// Mix` failed with "missing agent 0 (have agent 1)", that agent having discovered its coordinator
// and announced; the same two runs started by hand with TESSERA_DDS_LOG=1 failed the same way,
// and the deaf agent's log held 200,889 such receive errors in 20 s.
// `scripts/dds_staggered_runs.sh 118 30 0.2` (30 runs 0.2 s apart on one domain) reproduces it
// on demand without shm_segment_keeper.hpp: with `EXTRA="--transport shm"` 16 of 30 runs failed
// (load 10-14), and each of the 16 names the stuck listener; with it, 3 of 210 (7 batches, load
// 14-24) against 64 of 210 without.
//
// Avoided at its cause: a deleted participant's segment stays readable (shm_segment_keeper.hpp),
// so the retried message is read as soon as the name is back. Also, where UDP is on, discovery
// goes over UDP (discover_over_udp, transport/qos.hpp), so a deleted participant's last messages
// (discovery, to every participant of the domain) do not reach shared-memory ports at all.
// Still possible: a reader that reads a dead sender's message after a peer's Fast DDS watchdog
// removed the restored name (it does so >= 5 s after it last saw the sender alive).
//
// What: from the first participant of the process on, Fast DDS's warnings go to a consumer
// that counts these receive errors (and prints every warning and error as Fast DDS does when
// TESSERA_DDS_LOG=1, errors only otherwise, as by default). A timed-out wait
// (transport/run_failure.hpp) and a peer declared lost for silence (transport/peer_tracking.cpp:
// the silence may be this process's own stuck port) append shm_receive_note() to their message.

#include <cstdint>
#include <string>

namespace tessera::transport {

/// Installs the counting consumer once per process (idempotent, thread safe).
void watch_fastdds_log();

/// Receive errors "No such file or directory" counted so far (0 before watch_fastdds_log()).
std::uint64_t shm_receive_failures();

/// "" when shm_receive_failures() is 0, else a sentence naming the defect and the count.
std::string shm_receive_note();

}  // namespace tessera::transport
