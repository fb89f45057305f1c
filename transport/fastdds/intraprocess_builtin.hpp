#pragma once
// Keeps Fast DDS's built-in traffic between participants of one process off its intra-process
// path.
//
// Why: with Fast DDS 2.9's default intra-process delivery (INTRAPROCESS_FULL), a participant
// hands its built-in messages (participant and endpoint discovery, writer liveliness) to the
// other participants of its process by calling their readers directly. Each participant's event
// thread asserts its writers' liveliness while holding that participant's PDP mutex, and the
// receiving side's WLPListener takes the receiver's PDP mutex: two participants of one process
// whose assertions fall at the same moment deadlock (A holds A's mutex and waits for B's, B
// holds B's and waits for A's; upstream Fast-DDS PR 3115, "Fixing deadlock in WLP", which
// Debian's 2.9.1 does not have). Both event threads then stay blocked, no timer of either
// participant runs again, and deleting either waits forever for its event thread
// (ResourceEvent::unregister_timer): the teardown guard ended such a process after 5 s
// (`DdsReadyBarrier`'s "teardown overrun", gdb stacks in docs/dds-runtime.md). Processes with
// two participants: an online agent (its graph stream and its online channel) and every test
// that holds several sessions. With built-in traffic going over the transport (UDP or shared
// memory, as between processes) no thread of one participant ever takes another's PDP mutex;
// user data still goes intra-process.

namespace tessera::transport {

/// Before a participant is created: loads Fast DDS's XML profiles (as creating the first
/// participant would) and, if the library's intra-process delivery is still Fast DDS's default
/// INTRAPROCESS_FULL, sets it to INTRAPROCESS_USER_DATA_ONLY. A setting made by an XML profile
/// or by the caller (INTRAPROCESS_OFF or USER_DATA_ONLY) is kept. Idempotent; call it before
/// every participant creation (create_participant_with_discovery_port does).
void keep_builtin_traffic_off_intraprocess();

}  // namespace tessera::transport
