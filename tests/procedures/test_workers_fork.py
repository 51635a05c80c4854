"""The local worker pool forks on Linux, safely: one library thread, the Allan engine, HDF5.

docs/performance.md, "Workers": a forked worker starts in milliseconds with this process's
imports and compiled kernels; what a fork would carry over wrongly (the Allan engine's threads,
OpenBLAS's thread count, h5py's lock) is dealt with, and the results equal the serial ones bit
for bit (tests/procedures/test_p1_workers.py for P1's windows, test_p2_twin.py for P2's units).
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time

import h5py
import numpy as np
import pytest

from imucalib.analysis import _allan_engine
from imucalib.analysis._allan_kernels import backend_name
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.procedures.common import workers
from imucalib.procedures.common.workers import (
    START_VARIABLE,
    THREAD_VARIABLES,
    in_worker,
    local_pool,
    set_blas_threads,
    share_with_workers,
    start_method,
)

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork: Linux only")

#: Set by a test in this process before the pool starts: a forked worker sees the value, a
#: spawned one the default (it imports this module anew).
MARK = "default"


def _worker_view(_: object = None) -> dict[str, object]:
    """What a worker sees of its process (a module-level function: it pickles)."""
    from h5py._objects import phil

    return {"pid": os.getpid(), "mark": MARK, "in_worker": in_worker(),
            "env": {k: os.environ.get(k) for k in THREAD_VARIABLES},
            "blas": set_blas_threads(1), "phil_owned": bool(phil._is_owned())}


def _read_dataset(job: list[str]) -> list[float]:
    """Open a file by its path in a worker and sum a dataset (``there`` of share_with_workers)."""
    with h5py.File(job[0], "r") as f:
        return [float(np.sum(f["x"][()]))]


def _pid_of(job: list[int]) -> list[int]:
    return [os.getpid()] * len(job)


def _refuse(job: list[int]) -> list[int]:
    raise InvalidInputError(f"job {job} refused")


def test_start_method_is_fork_on_linux_unless_asked(monkeypatch):
    monkeypatch.delenv(START_VARIABLE, raising=False)
    assert start_method() == ("fork" if sys.platform.startswith("linux") else "spawn")
    assert start_method("spawn") == "spawn"
    monkeypatch.setenv(START_VARIABLE, "spawn")
    assert start_method() == "spawn"
    with pytest.raises(ConfigurationError, match="auto, fork or spawn"):
        start_method("thread")


@linux
def test_a_forked_worker_has_one_thread_of_each_library_and_this_process_keeps_its_own(
        monkeypatch):
    monkeypatch.delenv(START_VARIABLE, raising=False)
    monkeypatch.setattr(sys.modules[__name__], "MARK", "set in the parent")
    mine = set_blas_threads(2)  # this process: two BLAS threads (then restored)
    try:
        env = {k: os.environ.get(k) for k in THREAD_VARIABLES}
        with local_pool(2) as pool:
            seen = [pool.submit(_worker_view).result() for _ in range(4)]
        assert {k: os.environ.get(k) for k in THREAD_VARIABLES} == env
        assert set_blas_threads(2) == [2] * len(mine)  # not changed by the workers
    finally:
        set_blas_threads(mine)
    assert not in_worker()
    for view in seen:
        assert view["pid"] != os.getpid()
        assert view["mark"] == "set in the parent"  # forked: this process's memory
        assert view["in_worker"] and not view["phil_owned"]
        assert set(view["env"].values()) == {"1"}
        assert view["blas"] and set(view["blas"]) == {1}  # numpy's OpenBLAS at least


def test_spawn_stays_available():
    # what runs in a spawned worker must import there: library functions, not this module's
    with local_pool(1, start="spawn") as pool:
        assert pool.submit(workers.in_worker).result()
        assert pool.submit(os.getenv, "IMUCALIB_THREADS").result() == "1"
        assert pool.submit(os.getpid).result() != os.getpid()


@linux
def test_forked_workers_open_a_file_this_process_holds_open(tmp_path, monkeypatch):
    """HDF5 in a forked worker: the file this process has open is opened again by path there.

    Also from another thread of this process at the fork: the fork happens under h5py's lock.
    """
    monkeypatch.delenv(START_VARIABLE, raising=False)
    paths = []
    for k in range(6):
        p = tmp_path / f"f{k}.h5"
        with h5py.File(p, "w") as f:
            f["x"] = np.arange(10_000, dtype=np.float64) * (k + 1)
        paths.append(str(p))
    with h5py.File(paths[0], "r") as held:
        before = float(np.sum(held["x"][()]))
        got = share_with_workers(paths, [1] * 6, 2, there=_read_dataset, n_jobs=6)
        assert float(np.sum(held["x"][()])) == before  # this process's file still reads
    assert got == [float(np.sum(np.arange(10_000) * (k + 1.0))) for k in range(6)]


@linux
def test_the_workers_take_the_largest_job_first_and_this_process_the_smallest(monkeypatch):
    monkeypatch.delenv(START_VARIABLE, raising=False)

    def here(item: int) -> int:
        time.sleep(0.4)  # time for the worker to start, even on a loaded machine
        return os.getpid()

    pids = share_with_workers(list(range(6)), [1, 1, 1, 100, 1, 1], 2, here=here, there=_pid_of,
                              n_jobs=6)
    assert pids[3] != os.getpid()  # the largest: a worker's
    assert pids[5] == os.getpid()  # the smallest, last: this process's


def test_an_error_in_a_worker_ends_the_run():
    with pytest.raises(InvalidInputError, match="refused"):
        share_with_workers(list(range(8)), [1] * 8, 2, here=lambda x: time.sleep(0.05),
                           there=_refuse)


def test_one_process_or_one_job_starts_no_pool(monkeypatch):
    def no_pool(*args, **kwargs):
        raise AssertionError("a pool was started")

    monkeypatch.setattr(workers, "local_pool", no_pool)
    assert share_with_workers([3, 1, 2], [1, 1, 1], 1, there=sorted) == [3, 1, 2]
    assert share_with_workers([3], [1], 4, there=sorted) == [3]


def _phase_digest(queue: multiprocessing.Queue) -> None:  # type: ignore[type-arg]
    rate = np.random.default_rng(7).standard_normal(_allan_engine.PARALLEL_PHASE_MIN + 4097)
    out = np.empty(rate.size)
    _allan_engine.integrate_phase(rate, 0.25, 0.01, out)
    queue.put(out.tobytes())


@linux
@pytest.mark.skipif(backend_name() != "numba", reason="the Allan engine's threads: numba only")
def test_the_allan_engine_works_in_a_child_forked_after_it_ran_here(monkeypatch):
    """Its thread pool, made here, is dropped in the child (at-fork hook): no deadlock.

    Without the hook the child inherits an executor that counts two idle threads that do not
    exist in the child, starts none, and waits for ever on its first job.
    """
    monkeypatch.setenv("IMUCALIB_THREADS", "2")
    context = multiprocessing.get_context("fork")
    here = context.Queue()
    _phase_digest(here)
    expected = here.get(timeout=10)
    assert _allan_engine._POOL is not None  # made and used in this process
    there = context.Queue()
    child = context.Process(target=_phase_digest, args=(there,))
    child.start()
    try:
        got = there.get(timeout=60)
    finally:
        child.join(10)
        if child.is_alive():
            child.kill()
            child.join()
    assert child.exitcode == 0
    assert got == expected  # the same bits in the child as here


@linux
def test_this_process_shares_with_one_thread_and_gets_its_own_back(monkeypatch):
    """While it shares work this process is one core's worth too; its settings come back."""
    monkeypatch.delenv(START_VARIABLE, raising=False)
    monkeypatch.setenv("IMUCALIB_THREADS", "2")
    mine = set_blas_threads(2)
    seen: list[tuple[list[int], str | None]] = []

    def here(item: int) -> int:
        seen.append((set_blas_threads(1), os.environ.get("IMUCALIB_THREADS")))
        return item

    try:
        assert share_with_workers(list(range(8)), [1] * 8, 2, here=here, there=sorted) == \
            list(range(8))
        assert set_blas_threads(2) == [2] * len(mine)  # restored
    finally:
        set_blas_threads(mine)
    assert os.environ["IMUCALIB_THREADS"] == "2"
    assert seen and all(set(blas) == {1} and allan == "1" for blas, allan in seen)
