"""Local worker processes for an analysis: one pool recipe for every procedure that splits.

:func:`local_pool` gives a :class:`~concurrent.futures.ProcessPoolExecutor` whose processes
are *forked* from this one where that is safe (Linux) and *spawned* elsewhere or when asked
(:data:`START_VARIABLE`). A forked worker starts in milliseconds with everything this process
has imported and compiled (the numba kernels); a spawned one pays an interpreter and the
imports, 1.7–2 s, which made two workers slower than one process on two cores
(docs/performance.md, "Workers"). What a fork would otherwise carry over wrongly is dealt with:

- **threads**: the pool forks all its workers at once, before it starts a thread of its own;
  the Allan engine's thread pool, whose threads do not survive a fork, is dropped in the child
  by an at-fork hook (:mod:`imucalib.analysis._allan_engine`) and no kernel uses numba's
  threading layer (``parallel=True``); OpenBLAS stops its threads before a fork (its own
  at-fork handler) and a worker restarts it with one thread (:func:`set_blas_threads`);
- **HDF5**: the fork happens under h5py's global lock, so that no other thread is inside the
  library at that moment (the pattern of :mod:`imucalib.io._probe`); the worker releases the
  inherited lock and opens each recording itself, by path, read-only;
- **garbage**: this process's objects are frozen for the fork (:func:`gc.freeze`), so a worker's
  garbage collector never finalises one of them (an HDF5 file or a temporary directory of this
  process).

Each worker is asked for one thread of every numerical library it uses: each worker is one
core's worth of work, and the libraries' own threads would make the processes fight over the
cores. :func:`share_with_workers` shares a list of items between this process (with one thread
too, meanwhile) and the workers, the jobs taken largest first from one queue. What runs in a
worker must be a module-level function of picklable arguments (spawned workers import it), and
its results must not depend on which process computed them: the same inputs give the same
values bit for bit (``docs/performance.md``, "Workers").
"""

from __future__ import annotations

import ctypes
import functools
import gc
import multiprocessing
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, wait
from contextlib import contextmanager
from typing import Any, TypeVar

from imucalib.errors import ConfigurationError

__all__ = ["START_VARIABLE", "THREAD_VARIABLES", "balanced_groups", "in_worker", "local_pool",
           "one_thread", "set_blas_threads", "share_with_workers", "start_method"]

_T = TypeVar("_T")
_R = TypeVar("_R")

#: The environment variables that set the thread count of BLAS, OpenMP, Blosc, numba and the
#: Allan engine (``IMUCALIB_THREADS``) in a worker.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "BLOSC_NTHREADS", "NUMBA_NUM_THREADS", "IMUCALIB_THREADS")

#: The environment variable that chooses how the workers start: ``fork`` or ``spawn``; unset
#: (or ``auto``), fork on Linux and spawn elsewhere (:func:`start_method`).
START_VARIABLE = "IMUCALIB_WORKER_START"

#: The names under which OpenBLAS builds export their thread-count setter (plain, numpy's
#: 64-bit-integer ``scipy_openblas64_`` and scipy's ``scipy_openblas``).
_BLAS_SETTERS = ("openblas_set_num_threads", "scipy_openblas_set_num_threads64_",
                 "scipy_openblas_set_num_threads", "openblas_set_num_threads64_")
_BLAS_GETTERS = ("openblas_get_num_threads", "scipy_openblas_get_num_threads64_",
                 "scipy_openblas_get_num_threads", "openblas_get_num_threads64_")


def start_method(start: str | None = None) -> str:
    """Return how :func:`local_pool` starts its workers: ``"fork"`` or ``"spawn"``.

    Parameters
    ----------
    start : {"auto", "fork", "spawn"}, optional
        Default: the environment variable :data:`START_VARIABLE`, else ``"auto"``: fork on
        Linux (where a forked child is a safe copy of this process, module docstring), spawn
        elsewhere (macOS's system libraries are not safe to use after a fork).

    Raises
    ------
    ConfigurationError
        An unknown method, or ``fork`` on a platform without it.
    """
    wanted = (start if start is not None else os.environ.get(START_VARIABLE, "")).strip().lower()
    if wanted in ("", "auto"):
        return "fork" if sys.platform.startswith("linux") else "spawn"
    if wanted not in ("fork", "spawn"):
        raise ConfigurationError(f"worker start method must be auto, fork or spawn "
                                 f"({START_VARIABLE}); got {wanted!r}")
    if wanted not in multiprocessing.get_all_start_methods():
        raise ConfigurationError(f"this platform cannot {wanted} worker processes "
                                 f"({START_VARIABLE}); use spawn")
    return wanted


def _loaded_openblas() -> list[ctypes.CDLL]:
    """Return the OpenBLAS libraries loaded in this process (numpy's, scipy's; Linux only)."""
    paths: set[str] = set()
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                name = line.rsplit(None, 1)[-1] if line.count(" ") >= 5 else ""
                if "openblas" in os.path.basename(name).lower() and ".so" in name:
                    paths.add(name)
    except OSError:
        return []
    libs = []
    for path in sorted(paths):
        try:  # RTLD_NOLOAD: a handle on the copy already loaded, never a second one
            libs.append(ctypes.CDLL(path, mode=getattr(os, "RTLD_NOLOAD", 0) | os.RTLD_LAZY))
        except OSError:
            continue
    return libs


def _symbol(lib: ctypes.CDLL, names: Sequence[str]) -> Any:
    for name in names:
        fn = getattr(lib, name, None)
        if fn is not None:
            return fn
    return None


def set_blas_threads(n: int | Sequence[int]) -> list[int]:
    """Set the thread count of every OpenBLAS loaded in this process; return the old counts.

    The environment variables (:data:`THREAD_VARIABLES`) are read when a library loads: in a
    forked worker the libraries are already loaded, so the count is set through OpenBLAS's
    own ``openblas_set_num_threads`` (what ``threadpoolctl`` does; it is not a dependency).
    `n` is one count for all, or a count per library as this function returned them (to
    restore them). A process without OpenBLAS loaded (or not on Linux) returns an empty list.
    """
    old = []
    k = 0
    for lib in _loaded_openblas():
        setter, getter = _symbol(lib, _BLAS_SETTERS), _symbol(lib, _BLAS_GETTERS)
        if setter is None or getter is None:
            continue
        getter.restype = ctypes.c_int
        old.append(int(getter()))
        setter.argtypes = [ctypes.c_int]
        setter(int(n) if isinstance(n, int) else int(n[k]))
        k += 1
    return old


@contextmanager
def one_thread() -> Iterator[None]:
    """Give this process one thread of OpenBLAS and of the Allan engine within the block.

    :func:`share_with_workers` runs this process's share so, as every worker runs: one core's
    worth of work each. The counts are restored at the end. OpenBLAS's multi-threaded
    reductions sum in another order than one thread: a P1 analysis with OpenBLAS's default
    threads differs from one with one thread by up to 2e-10 of a parameter's scale, so a
    serial analysis equals a shared one bit for bit when it runs within this block too
    (docs/performance.md, "Workers").
    """
    old_blas = set_blas_threads(1)
    old_allan = os.environ.get("IMUCALIB_THREADS")
    os.environ["IMUCALIB_THREADS"] = "1"
    try:
        yield
    finally:
        set_blas_threads(old_blas)
        if old_allan is None:
            os.environ.pop("IMUCALIB_THREADS", None)
        else:
            os.environ["IMUCALIB_THREADS"] = old_allan


_IN_WORKER = False  # set in the workers of local_pool by their initialiser


def in_worker() -> bool:
    """Say whether this process is a worker of :func:`local_pool` (its caches live that long)."""
    return _IN_WORKER


def _start_worker(forked: bool, initializer: Callable[..., object] | None,
                  initargs: tuple[Any, ...]) -> None:
    """Prepare a worker: one thread of every library, h5py's lock released; `initializer`."""
    global _IN_WORKER
    _IN_WORKER = True
    if forked:
        from h5py._objects import phil

        os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))  # read at each use (Allan)
        set_blas_threads(1)
        while phil._is_owned():  # the fork happened under the lock (_fork_workers)
            phil.release()
    if initializer is not None:
        initializer(*initargs)


@contextmanager
def local_pool(workers: int, *, start: str | None = None,
               initializer: Callable[..., object] | None = None,
               initargs: tuple[Any, ...] = ()) -> Iterator[ProcessPoolExecutor]:
    """Yield a pool of `workers` processes with one library thread each.

    Parameters
    ----------
    workers : int
        The processes.
    start : {"auto", "fork", "spawn"}, optional
        How they start (:func:`start_method`; default fork on Linux, spawn elsewhere).
    initializer, initargs
        Called in each worker as it starts, after the pool's own preparation; `initargs` may
        hold :mod:`multiprocessing` locks and shared arrays (passed at the start, not pickled
        into jobs).

    Notes
    -----
    Forked workers are all started here, before the pool's own threads and before anything is
    submitted (module docstring), and set their libraries to one thread themselves. Spawned
    ones start on the first submission, with the variables of :data:`THREAD_VARIABLES` set to
    1 in this process meanwhile (restored when the pool is shut down; this process keeps its
    own threads).

    Raises
    ------
    ConfigurationError
        An unknown or unavailable start method.
    """
    method = start_method(start)
    context = multiprocessing.get_context(method)
    init = functools.partial(_start_worker, method == "fork", initializer, initargs)
    if method == "fork":
        with ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                 initializer=init) as pool:
            _fork_workers(pool)
            yield pool
        return
    old = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    try:
        with ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                 initializer=init) as pool:
            yield pool
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _fork_workers(pool: ProcessPoolExecutor) -> None:
    """Fork every worker of `pool` now: under h5py's lock, with this process's objects frozen.

    A fork-started :class:`~concurrent.futures.ProcessPoolExecutor` forks all its workers at
    the first submission, before it starts its management thread; a no-op is that submission.
    """
    from h5py._objects import phil

    gc.freeze()  # a worker's collector never finalises an object of this process
    try:
        with phil:  # no other thread of this process is inside HDF5 at the fork
            pool.submit(int)
    finally:
        gc.unfreeze()


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


class _Jobs:
    """The jobs of :func:`share_with_workers`, taken from both ends of one shared queue.

    ``order`` lists the jobs largest first; the workers take from its front, this process from
    its back, each under one lock shared by the processes, so every job is taken exactly once
    and none waits for a busy process while another is idle.
    """

    def __init__(self, lock: Any, ends: Any, order: Sequence[int], jobs: Sequence[list[Any]],
                 there: Callable[[list[Any]], list[Any]]) -> None:
        self.lock, self.ends, self.order, self.jobs, self.there = lock, ends, order, jobs, there

    def take(self, front: bool) -> int | None:
        """Return the next job from the front (a worker) or the back (this process), or None."""
        with self.lock:
            first, last = self.ends[0], self.ends[1]
            if first > last:
                return None
            if front:
                self.ends[0] = first + 1
                return self.order[first]
            self.ends[1] = last - 1
            return self.order[last]

    def close(self) -> None:
        """Leave no job to take (after an error)."""
        with self.lock:
            self.ends[0], self.ends[1] = 1, 0


_JOBS: _Jobs | None = None  # a worker's view of its pool's jobs (_adopt_jobs)


def _adopt_jobs(lock: Any, ends: Any, order: Sequence[int], jobs: Sequence[list[Any]],
                there: Callable[[list[Any]], list[Any]]) -> None:
    global _JOBS
    _JOBS = _Jobs(lock, ends, order, jobs, there)


def _run_next_job() -> tuple[int, list[Any]] | None:
    """Take the next job from the front and run it in this worker; None when none is left."""
    assert _JOBS is not None
    g = _JOBS.take(front=True)
    return None if g is None else (g, _JOBS.there(_JOBS.jobs[g]))


def share_with_workers(items: Sequence[_T], sizes: Sequence[int], workers: int, *,
                       there: Callable[[list[_T]], list[_R]],
                       here: Callable[[_T], _R] | None = None,
                       done: Callable[[int], None] | None = None,
                       n_jobs: int | None = None, start: str | None = None) -> list[_R]:
    """Process `items` in this process and `workers` − 1 others; the results in order.

    Parameters
    ----------
    items : sequence
        What to process.
    sizes : sequence of int
        Each item's cost (samples, units): the jobs are runs of consecutive items of about
        equal total size (:func:`balanced_groups`).
    workers : int
        Processes, this one included (:func:`local_pool` starts the others).
    there : callable
        Processes a job (a list of items) in a worker, returning their results in order: a
        picklable module-level function, or a :func:`functools.partial` of one.
    here : callable, optional
        Processes one item in this process (default: `there` on the job).
    done : callable, optional
        Called with the number of items just finished (this process and the workers).
    n_jobs : int, optional
        About how many jobs (default four per process).
    start : str, optional
        The workers' start method (:func:`start_method`).

    Notes
    -----
    The jobs are queued largest first; the workers take them from the front, this process from
    the back (the smallest), one at a time, until none is left: the longest jobs start first
    and no process waits while a job is left (a job is taken under a lock the processes share,
    once). `here` and `there` must give the same result for an item, as a serial loop would:
    then the list is the one a serial loop gives. An exception in either ends the whole run
    (no job is taken after it).
    """
    groups = balanced_groups(sizes, n_jobs or 4 * workers)
    jobs = [[items[i] for i in group] for group in groups]
    out: dict[int, _R] = {}

    def finished(g: int, results: list[_R]) -> None:
        for i, result in zip(groups[g], results, strict=True):
            out[i] = result
        if done is not None:
            done(len(groups[g]))

    def here_job(g: int) -> None:
        if here is None:
            finished(g, there(jobs[g]))
            return
        for i in groups[g]:
            out[i] = here(items[i])
            if done is not None:
                done(1)

    if workers < 2 or len(groups) < 2:
        for g in range(len(groups)):
            here_job(g)
        return [out[i] for i in range(len(items))]
    order = sorted(range(len(groups)), key=lambda g: -sum(sizes[i] for i in groups[g]))
    context = multiprocessing.get_context(start_method(start))
    lock = context.Lock()
    ends = context.RawArray(ctypes.c_long, [0, len(groups) - 1])
    shared = _Jobs(lock, ends, order, jobs, there)
    with one_thread(), local_pool(min(workers - 1, len(groups) - 1), start=start,
                                        initializer=_adopt_jobs,
                                        initargs=(lock, ends, order, jobs, there)) as pool:
        # one task per job: each takes the next job from the front, or returns None
        pending = {pool.submit(_run_next_job) for _ in groups}

        def collect(timeout: float | None) -> None:
            nonlocal pending
            ready, pending = wait(pending, timeout=timeout)
            for fut in ready:
                got = fut.result()
                if got is not None:
                    finished(*got)

        try:
            while (taken := shared.take(front=False)) is not None:
                here_job(taken)
                collect(0)
            while pending:
                collect(None)
        except BaseException:
            shared.close()
            for fut in pending:
                fut.cancel()
            raise
    return [out[i] for i in range(len(items))]
