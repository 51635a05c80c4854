"""P1's windows reduced in forked worker processes, the result the serial one bit for bit.

The plumbing between :func:`~.observations.extract_p1_observations` and the shared workers
(:mod:`~imucalib.procedures.common.workers`): which windows go to the workers, how a worker
opens the recording once for all the windows it takes, and when a run is too small to share
(docs/performance.md, "Workers").

Contents
--------
:func:`observe_parallel`, :data:`PARALLEL_ROWS_MIN`
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

from imucalib.io.reader import StepRecord
from imucalib.io.streams import DEVICE_IMU
from imucalib.procedures.p1.window_reduction import P1Processing, WindowReducer
from imucalib.procedures.p1.windows import WindowObservation

__all__ = ["PARALLEL_ROWS_MIN", "observe_parallel"]


def _observe_steps(path: str, sensor_id: str, opt: P1Processing, sample_rate_hz: float,
                   todo: Sequence[tuple[StepRecord, str, bool]]) -> list[WindowObservation]:
    """Reduce some steps of a recording in a worker process (:func:`observe_parallel`).

    A worker of :func:`~imucalib.procedures.common.workers.local_pool` opens the recording
    (by its path) once for all the jobs it takes; elsewhere it is opened for this call.
    """
    from imucalib.io.opening import open_recording
    from imucalib.procedures.common.workers import in_worker

    key = (path, sensor_id, opt)
    if in_worker():
        ex = _WORKER_EXTRACTORS.get(key)
        if ex is None:  # open for the pool's life: the worker ends with the pool
            ex = _WORKER_EXTRACTORS[key] = WindowReducer(open_recording(path), sensor_id, opt)
        ex.sample_rate_hz = sample_rate_hz  # the parent's: the same time base as in one process
        return [ex.observe(*job) for job in todo]
    with open_recording(path) as rec:
        ex = WindowReducer(rec, sensor_id, opt)
        ex.sample_rate_hz = sample_rate_hz
        return [ex.observe(*job) for job in todo]


#: A worker's open recordings (:func:`_observe_steps`), by (path, IMU, processing).
_WORKER_EXTRACTORS: dict[tuple[str, str, P1Processing], WindowReducer] = {}

#: IMU rows (of the windows after the first) below which ``workers`` > 1 reduces them in this
#: process alone: a worker's fixed cost (its fork, opening the recording, the copy-on-write of
#: the pages it touches: about 0.1 s of CPU) is about what it saves on fewer (two processes
#: lose below about 200,000 rows and gain 1.1× at best at 420,000–490,000; docs/performance.md,
#: "Workers").
PARALLEL_ROWS_MIN = 1 << 19


def observe_parallel(ex: WindowReducer, todo: list[tuple[StepRecord, str, bool]], workers: int,
                     tick: Callable[[int], None]) -> list[WindowObservation]:
    """Reduce the steps in this process and `workers` − 1 forked ones; the serial result.

    The first step is reduced here first: it fixes what later windows use (the sample rate of
    a recording that does not state it), and the workers, forked after it, start with its
    compiled kernels. The rest are shared with the workers
    (:func:`~imucalib.procedures.common.workers.share_with_workers`: jobs of consecutive steps
    of about equal samples, the longest taken first by the workers, the shortest by this
    process) unless they hold fewer than :data:`PARALLEL_ROWS_MIN` IMU rows (then this process
    reduces them alone). Every window is reduced by the same code from the same samples and
    sample rate: the observations equal the serial ones bit for bit
    (tests/procedures/test_p1_workers.py).
    """
    from imucalib.procedures.common.workers import share_with_workers

    first = ex.observe(*todo[0])
    tick(1)
    rest = todo[1:]
    sizes = [max(1, _rows(ex, job[0])) for job in rest]
    if sum(sizes) < PARALLEL_ROWS_MIN:
        workers = 1
    there = functools.partial(_observe_steps, str(ex.rec.path), ex.sensor, ex.opt,
                              ex.sample_rate_hz)
    return [first, *share_with_workers(rest, sizes, workers, here=lambda item: ex.observe(*item),
                                       there=there, done=tick)]


def _rows(ex: WindowReducer, step: StepRecord) -> int:
    i0, i1 = ex.rec.row_range(DEVICE_IMU, ex.sensor, step.valid_start_s, step.valid_end_s)
    return int(i1 - i0)
