#pragma once
/// One BLAS thread for timed runs. OpenBLAS (Debian's libblas.so.3 alternative) starts one worker
/// thread per core when it loads; on a 2-core machine the idle worker spins in sched_yield beside a
/// solve (10% of a coupled solve's samples), which disturbs the other core's timings. Unless the
/// user set OPENBLAS_NUM_THREADS, contactbench sets one thread for itself and for the processes
/// it starts (peers, `command` solvers, generated scripts read the environment).

namespace cb {

/// Sets OPENBLAS_NUM_THREADS=1 in the environment and calls openblas_set_num_threads(1), unless
/// OPENBLAS_NUM_THREADS is already set (the user's choice is kept). The OpenBLAS functions are
/// found at run time, so any BLAS alternative links and runs (then nothing is changed).
void limit_blas_threads();

/// openblas_get_num_threads(), or 0 when the BLAS in the process is not OpenBLAS.
int blas_threads();

}  // namespace cb
