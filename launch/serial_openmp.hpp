#pragma once
// An agent process runs OpenMP parallel regions on its own thread.
//
// The only OpenMP in an agent is CHOLMOD's (Debian's 3.0.x): a few loops of its supernodal
// factorization (zeroing the factor, scattering the matrix and the descendants' updates into
// it) are parallel regions of a fixed 4 threads (CHOLMOD_OMP_NUM_THREADS, set when CHOLMOD was
// compiled; OMP_NUM_THREADS does not change it), whose workers spin between regions. In a run
// of several agents on one host every agent would bring its own team, competing with the
// others for the cores: on city10000 with 5 agents on 2 cores, the refinement's supernodal
// factors (distributed/interface_solve.hpp) cost the run ~0.35 CPU-s more with the teams than
// without (docs/newton-refine.md). The BLAS that does the factor's arithmetic is serial anyway.

namespace tessera::launch {

/// Makes every OpenMP parallel region of this process inactive (one thread): sets OpenMP's
/// max-active-levels to 0 through the OpenMP runtime loaded with CHOLMOD, found at run time (no
/// link dependency). Process-wide; call once, early. False when no OpenMP runtime is loaded
/// (then there are no parallel regions to restrict).
/// Also makes CHOLMOD's regions run inline on the calling thread (GOMP_parallel, defined in
/// serial_openmp.cpp), without libgomp's per-region team of one.
bool serial_openmp();

/// Whether serial_openmp() was called in this process (regions then run inline).
bool openmp_regions_run_inline();

}  // namespace tessera::launch
