"""P1's windows reduced in several processes give the serial observations bit for bit."""

from __future__ import annotations

import dataclasses
import itertools
import os
import sys

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.io import open_recording
from imucalib.procedures import registry
from imucalib.procedures.common.workers import START_VARIABLE, balanced_groups
from imucalib.procedures.p1 import parallel as p1_parallel
from imucalib.procedures.p1.observations import extract_p1_observations


def _fields(obs):
    return [dataclasses.asdict(w) for w in obs.windows]


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


@pytest.fixture
def shared(monkeypatch):
    """Share every recording's windows with the workers, however small (the test runs are)."""
    monkeypatch.setattr(p1_parallel, "PARALLEL_ROWS_MIN", 0)
    monkeypatch.delenv(START_VARIABLE, raising=False)


@pytest.mark.parametrize("start", ["auto", "spawn"])
def test_two_workers_give_the_serial_observations_and_progress(consumer_run, shared, monkeypatch,
                                                               start):
    monkeypatch.setenv(START_VARIABLE, start)  # auto: forked on Linux
    fractions: list[float] = []
    with open_recording(consumer_run) as rec:
        serial = extract_p1_observations(rec)
        parallel = extract_p1_observations(rec, workers=2, progress=fractions.append)
        three = extract_p1_observations(rec, workers=3)
    assert len(parallel.windows) == len(serial.windows) > 3
    assert _same(_fields(parallel), _fields(serial))
    assert _same(_fields(three), _fields(serial))
    assert parallel.sample_rate_hz == serial.sample_rate_hz
    assert parallel.cutoff_hz == serial.cutoff_hz
    assert parallel.notes == serial.notes
    assert all(b > a for a, b in itertools.pairwise(fractions)) and fractions[-1] == 1.0


def test_the_windows_go_to_forked_workers(consumer_run, shared, monkeypatch):
    """The pool is started once, with fork on Linux, and its workers reduce windows."""
    from imucalib.procedures.common import workers

    started: list[str] = []
    pids: list[int] = []
    real_pool, real_share = workers.local_pool, workers.share_with_workers

    def pool(*args, **kwargs):
        started.append(workers.start_method(kwargs.get("start")))
        return real_pool(*args, **kwargs)

    def share(items, sizes, n, *, there, **kwargs):
        def where(job):  # a closure: fine for a forked worker, which inherits it
            return [(os.getpid(), w) for w in there(job)]

        serial_here = kwargs.pop("here")

        def here(item):
            return (os.getpid(), serial_here(item))

        out = real_share(items, sizes, n, there=where, here=here, **kwargs)
        pids.extend(pid for pid, _ in out)
        return [w for _, w in out]

    monkeypatch.setattr(workers, "local_pool", pool)
    monkeypatch.setattr(workers, "share_with_workers", share)
    with open_recording(consumer_run) as rec:
        serial = extract_p1_observations(rec)
        parallel = extract_p1_observations(rec, workers=2)
    assert _same(_fields(parallel), _fields(serial))
    assert started == [("fork" if sys.platform.startswith("linux") else "spawn")]
    if sys.platform.startswith("linux"):
        assert os.getpid() in pids and set(pids) - {os.getpid()}  # both reduced windows


def test_a_small_recording_is_reduced_here_alone(consumer_run, monkeypatch):
    """Below PARALLEL_ROWS_MIN IMU rows a pool costs more than it saves: none is started."""
    from imucalib.procedures.common import workers

    def no_pool(*args, **kwargs):
        raise AssertionError("a pool was started")

    monkeypatch.setattr(workers, "local_pool", no_pool)
    monkeypatch.setattr(p1_parallel, "PARALLEL_ROWS_MIN", 1 << 40)
    with open_recording(consumer_run) as rec:
        serial = extract_p1_observations(rec)
        two = extract_p1_observations(rec, workers=2)
    assert _same(_fields(two), _fields(serial))


def test_calibrate_option_workers_gives_the_same_parameters(consumer_run, shared):
    p1 = registry.get("p1")
    one = p1.analyze(consumer_run, options={"workers": 1})
    two = p1.analyze(consumer_run, options={"workers": 2})
    assert [(r.name, r.value, r.std) for r in one.parameter_rows()] == \
        [(r.name, r.value, r.std) for r in two.parameter_rows()]
    with pytest.raises(InvalidInputError, match="--workers must be ≥ 1; got 0"):
        p1.analyze(consumer_run, options={"workers": 0})


@pytest.mark.parametrize(("sizes", "n"), [([5] * 10, 4), ([100, 1, 1, 1, 100, 1], 3),
                                          ([1], 8), ([3, 3], 1)])
def test_balanced_groups_cover_every_index_once_in_order(sizes, n):
    groups = balanced_groups(sizes, n)
    assert [i for g in groups for i in g] == list(range(len(sizes)))
    assert 1 <= len(groups) <= max(1, min(n, len(sizes))) + 1
    assert all(g for g in groups)


def test_share_with_workers_returns_the_items_in_order_and_counts_them():
    from imucalib.procedures.common.workers import share_with_workers

    items = list(range(30))
    counted: list[int] = []
    # `sorted` is a picklable function of a job (an ascending run of items) that returns it
    got = share_with_workers(items, [1] * 30, 2, here=lambda x: x, there=sorted,
                             done=counted.append)
    assert got == items and sum(counted) == 30


def test_share_with_workers_stops_at_an_error_here():
    from imucalib.procedures.common.workers import share_with_workers

    def here(x: int) -> int:
        raise InvalidInputError(f"item {x} refused")

    with pytest.raises(InvalidInputError, match="refused"):
        share_with_workers(list(range(40)), [1] * 40, 2, here=here, there=sorted)
