#pragma once
// How a process that used Fast DDS ends once its participant is deleted.
//
// Why: Fast DDS 2.9's DomainParticipantFactory destructor, a static destructor run at exit,
// sleeps 100 ms (seen with gdb), which every process of a run paid at its end. Nothing of
// Tessera's needs static destructors after the participant is gone, so the process skips them.

namespace tessera::transport {

/// Flushes stdout and stderr and ends the process with `code` WITHOUT running static
/// destructors. Call only after the participant is deleted (Session::close): nothing is left
/// in /dev/shm then.
[[noreturn]] void exit_process(int code);

}  // namespace tessera::transport
