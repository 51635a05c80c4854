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
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from typing import TypeVar

__all__ = ["balanced_groups", "local_pool", "share_with_workers"]

_T = TypeVar("_T")
_R = TypeVar("_R")

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


def balanced_groups(sizes: Sequence[int], n_groups: int) -> list[list[int]]:
    """Split indices 0 … len(sizes) − 1 into runs of about equal total size, in order.

    About `n_groups` runs (one more at most, where a large item ends a run); every run holds
    at least one index.
    """
    total = float(sum(sizes))
    target = total / max(1, min(n_groups, len(sizes)))
    groups: list[list[int]] = [[]]
    acc = 0.0
    for i, size in enumerate(sizes):
        if groups[-1] and acc + size / 2.0 > target * len(groups):
            groups.append([])
        groups[-1].append(i)
        acc += size
    return groups


def share_with_workers(items: Sequence[_T], sizes: Sequence[int], workers: int, *,
                       here: Callable[[_T], _R], there: Callable[[list[_T]], list[_R]],
                       done: Callable[[int], None] | None = None) -> list[_R]:
    """Process `items` in this process and `workers` − 1 spawned ones; results in order.

    The items go out as jobs of consecutive items of about equal `sizes`, about four per
    worker (:func:`balanced_groups`), to :func:`local_pool`; `there` (a picklable module-level
    function, or a :func:`functools.partial` of one) processes a job in a worker. While the
    workers start (an interpreter and the imports: a second or more) and take jobs from the
    front, this process takes jobs from the back that no worker has started — a job not yet
    started can be cancelled — and processes their items one by one with `here`, so no core
    waits for another's start-up. `here` and `there` must give the same result for an item:
    then the list is the one a serial loop gives. `done` is called with the number of items
    just finished. An exception in either ends the whole run (pending jobs cancelled).
    """
    out: dict[int, _R] = {}
    groups = balanced_groups(sizes, 4 * workers)
    with local_pool(workers - 1) as pool:
        futures = [pool.submit(there, [items[i] for i in group]) for group in groups]
        try:
            for g in range(len(groups) - 1, -1, -1):
                if not futures[g].cancel():
                    break
                for i in groups[g]:
                    out[i] = here(items[i])
                    if done is not None:
                        done(1)
            for g, fut in enumerate(futures):
                if fut.cancelled():
                    continue
                for i, result in zip(groups[g], fut.result(), strict=True):
                    out[i] = result
                if done is not None:
                    done(len(groups[g]))
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise
    return [out[i] for i in range(len(items))]
