#pragma once
// One BLAS caller at a time in the process. The BLAS is Debian 12's serial OpenBLAS 0.3.21
// (libopenblas0-serial), and two threads calling it at once get other bits than one thread now
// and then, its `blas_memory_alloc` lock notwithstanding: a loop of dsyrk + dpotrf + dgemm on two
// threads differed from the same calls on one thread in 3 of 900 repetitions, and with the
// in-process driver's two threads (DistributedOptions::threads) the distributed certificate's
// interface test, on the agents' supernodal factors, failed in 10 of 150 runs of
// online_engine_test TwoThreadsGiveTheSameStepsAsOne (0 of 160 with the reference BLAS
// preloaded; docs/online.md). Every call that reaches BLAS (CHOLMOD's supernodal factorizations
// and solves, the direct syrk) holds this lock: uncontended on one thread, and two threads
// serialize only their BLAS work.

#include <mutex>

namespace tessera {

/// The process-wide lock for calls into BLAS.
inline std::mutex& serial_blas_mutex() {
  static std::mutex m;
  return m;
}

/// Held while a call into BLAS (or into CHOLMOD's supernodal kernels, which call it) runs.
using SerialBlasLock = std::lock_guard<std::mutex>;

}  // namespace tessera
