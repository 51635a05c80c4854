"""Local worker processes for an analysis: one pool recipe for every procedure that splits.

:func:`local_pool` gives a :class:`~concurrent.futures.ProcessPoolExecutor` of *spawned*
processes (a forked child would inherit the HDF5 library's state, the BLAS threads' and the
Allan engine's thread pool, whose threads do not survive a fork), each asked for one thread of
every numerical library it uses: each worker is one core's worth of work, and the libraries'
own threads would make the processes fight over the cores (``bench/bench_p2.py`` measured the
pool slower than one process before this). What runs in a worker must be a module-level
function of picklable arguments, and its results must not depend on which process computed
them: the same inputs give the same values bit for bit (``docs/performance.md``, "Workers").
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

__all__ = ["local_pool"]

#: The environment variables that set the thread count of BLAS, OpenMP, Blosc, numba and the
#: Allan engine (``IMUCALIB_THREADS``) in a worker.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "BLOSC_NTHREADS", "NUMBA_NUM_THREADS", "IMUCALIB_THREADS")


@contextmanager
def local_pool(workers: int) -> Iterator[ProcessPoolExecutor]:
    """Yield a pool of `workers` spawned processes with one library thread each.

    The variables of :data:`THREAD_VARIABLES` are set while the pool starts its processes and
    restored when the pool is shut down (this process keeps its own threads).
    """
    old = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    for k in THREAD_VARIABLES:
        os.environ[k] = "1"
    try:
        with ProcessPoolExecutor(max_workers=workers,
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            yield pool
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
