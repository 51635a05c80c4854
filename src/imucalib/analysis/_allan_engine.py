"""Block drivers of the Allan-family estimators over a phase source (private).

A *phase source* holds the phase (angle) series x_0 … x_{n−1} of one channel, either in memory
(:class:`ArrayPhase`) or in a scratch file (:class:`imucalib.analysis.streaming.FilePhase`). The
drivers below read it in superblocks (multiples of :data:`~._allan_kernels.BLOCK` terms) and
call the kernels of :mod:`._allan_kernels`; the reduction blocks and their order do not depend
on the source or the superblock size, so a streamed computation equals the in-memory one bit for
bit.

Estimator sums (NIST SP 1065 [1]_, phase x, n = number of phase points, m = averaging factor):

=========  ===========================================  ==================================
kind       sum                                          number of terms
=========  ===========================================  ==================================
adev       Σ_k (x[km+2m] − 2x[km+m] + x[km])²            ⌈(n − 2m)/m⌉        eq. (7)
oadev      Σ_i (x[i+2m] − 2x[i+m] + x[i])²               n − 2m              eq. (11)
mdev       Σ_j (Σ_{i=j}^{j+m−1} x[i+2m] − 2x[i+m] + x[i])²   n − 3m + 1      eq. (14)
hdev       Σ_k (x[km+3m] − 3x[km+2m] + 3x[km+m] − x[km])²  ⌈(n − 3m)/m⌉      eq. (18)
ohdev      Σ_i (x[i+3m] − 3x[i+2m] + 3x[i+m] − x[i])²    n − 3m              eq. (20)
totdev     Σ_{i=1}^{n−2} (x*[i−m] − 2x*[i] + x*[i+m])²   n − 2               eq. (25)
=========  ===========================================  ==================================

x* is x extended by reflection at both ends: x*[−j] = 2x[0] − x[j] and
x*[n−1+j] = 2x[n−1] − x[n−1−j] for j = 1 … n−2.

References
----------
.. [1] W. J. Riley, "Handbook of Frequency Stability Analysis", NIST SP 1065, 2008.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from imucalib.analysis._allan_kernels import PHASE_BLOCK, backend_name, get_kernels

__all__ = [
    "PARALLEL_PHASE_MIN",
    "ArrayPhase",
    "PhaseSource",
    "integrate_phase",
    "n_terms",
    "read_reflected",
    "sum_nonoverlapping",
    "sum_overlapping",
    "sum_overlapping_rows",
    "sums_mdev",
    "sums_totdev",
]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

KINDS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev")


class PhaseSource(Protocol):
    """Read access to a phase series x_0 … x_{n−1} [angle units]."""

    @property
    def n_phase(self) -> int:
        """Number of phase points n."""

    @property
    def superblock(self) -> int:
        """Terms handled per kernel call (a multiple of BLOCK)."""

    def read(self, start: int, stop: int, step: int = 1) -> F64:
        """x[start:stop:step] as a contiguous float64 array (0 ≤ start ≤ stop ≤ n)."""

    def gather(self, start: int, offsets: I64, length: int) -> tuple[F64, I64]:
        """Windows x[start+o : start+o+length] (cut at n): one buffer and each window's start."""


class ArrayPhase:
    """A phase series held in memory (windows are views: nothing is copied)."""

    superblock = 1 << 16

    def __init__(self, phase: F64) -> None:
        self._x = phase

    @property
    def n_phase(self) -> int:
        return int(self._x.size)

    @property
    def array(self) -> F64:
        """The whole phase series (a view, not a copy)."""
        return self._x

    def read(self, start: int, stop: int, step: int = 1) -> F64:
        return np.ascontiguousarray(self._x[start:stop:step])

    def gather(self, start: int, offsets: I64, length: int) -> tuple[F64, I64]:
        return self._x, (start + offsets).astype(np.int64)


def n_terms(kind: str, m: NDArray[np.int64] | int, n_phase: int) -> NDArray[np.int64]:
    """Return the number of terms of estimator `kind` at averaging factors `m` (table above)."""
    mm = np.asarray(m, dtype=np.int64)
    n = np.int64(n_phase)
    if kind == "oadev":
        out = n - 2 * mm
    elif kind == "adev":
        out = -(-(n - 2 * mm) // mm)
    elif kind in ("mdev", "tdev"):
        out = n - 3 * mm + 1
    elif kind == "ohdev":
        out = n - 3 * mm
    elif kind == "hdev":
        out = -(-(n - 3 * mm) // mm)
    elif kind == "totdev":
        out = np.where(mm <= (n - 1) // 2, n - 2, 0)
    else:  # pragma: no cover - callers validate
        raise ValueError(kind)
    return np.maximum(np.asarray(out, dtype=np.int64), 0)


def _windows(ms: I64, order: int) -> tuple[I64, I64]:
    """Distinct offsets {0, m, 2m(, 3m)} and, per job, the index of each of its windows."""
    offsets = np.unique(np.concatenate([np.arange(order + 1, dtype=np.int64)[:, None] * ms]))
    win = np.searchsorted(offsets, np.arange(order + 1, dtype=np.int64)[None, :] * ms[:, None])
    if order == 2:
        win = np.concatenate([win, win[:, :1]], axis=1)  # unused 4th column
    return offsets.astype(np.int64), np.ascontiguousarray(win, dtype=np.int64)


#: Consecutive jobs kept together in one thread (the kernel chains τ, 2τ, 4τ over them).
CHAIN = 3


#: Terms (over all τ) below which the overlapping sums run in the calling thread: handing a short
#: window's sums to the pool cost more than they take (the window statistics of P1 and P2).
PARALLEL_SUM_MIN = 1 << 20


def _job_groups(n_terms: I64) -> list[I64]:
    """Split the jobs (τ values, ascending) between the worker threads.

    Consecutive jobs stay together in runs of :data:`CHAIN` so that the kernel can chain them
    (octave and 1-2-4 decade grids); the runs are dealt out largest first to the thread with the
    fewest terms so far. Which thread sums a τ does not change its result.
    """
    n_jobs = int(n_terms.size)
    workers = _worker_count() if backend_name() == "numba" else 1
    if int(n_terms.sum()) < PARALLEL_SUM_MIN:  # a window's few terms: the pool costs more
        workers = 1
    k = max(1, min(workers, -(-n_jobs // CHAIN)))
    if k == 1:
        return [np.arange(n_jobs, dtype=np.int64)]
    runs = [np.arange(a, min(a + CHAIN, n_jobs), dtype=np.int64) for a in range(0, n_jobs, CHAIN)]
    load = [0] * k
    members: list[list[int]] = [[] for _ in range(k)]
    for r in sorted(range(len(runs)), key=lambda r: -int(n_terms[runs[r]].sum())):
        g = load.index(min(load))
        members[g].append(r)
        load[g] += int(n_terms[runs[r]].sum())
    return [np.concatenate([runs[r] for r in sorted(m)]) for m in members if m]


def _worker_count() -> int:
    env = os.environ.get("IMUCALIB_THREADS")
    if env is not None and env.strip().isdigit():
        return max(1, int(env))
    return max(1, min(os.cpu_count() or 1, 8))


_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=_worker_count(), thread_name_prefix="allan")
    return _POOL


def _forget_pool_in_child() -> None:
    """Drop the parent's thread pool in a forked child: its threads did not survive the fork.

    The inherited executor still counts them (idle), so it would start none and a job would wait
    forever; the child makes its own pool on first use (a worker of
    :func:`~imucalib.procedures.common.workers.local_pool`, docs/performance.md "Workers").
    """
    global _POOL
    _POOL = None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool_in_child)


#: Samples below which the phase is integrated by one thread (the split costs a second pass).
PARALLEL_PHASE_MIN = 1 << 21


def integrate_phase(rate: F64, mean: float, dt: float, out: F64) -> None:
    """out_j = x_{j+1} of the canonical blocked phase sum (:mod:`._allan_kernels`) of `rate`.

    With the numba kernels, two or more worker threads and at least
    :data:`PARALLEL_PHASE_MIN` samples, the first half (whole phase blocks) is summed in full
    while another thread forms the local block sums of the second half; the carries of the
    second half are then chained from the first half's end and applied by two threads. Every
    value is formed by the same operations as in the one-thread kernel, so the result is
    identical bit for bit.
    """
    kern = get_kernels()
    n = rate.size
    n_blocks = n // PHASE_BLOCK
    if backend_name() != "numba" or _worker_count() < 2 or n < PARALLEL_PHASE_MIN:
        kern["phase"](rate, mean, dt, out, 0.0)
        return
    half = (n_blocks // 2) * PHASE_BLOCK
    tail_blocks = -(-(n - half) // PHASE_BLOCK)
    ends = np.empty(tail_blocks)
    first = _pool().submit(kern["phase"], rate[:half], mean, dt, out[:half], 0.0)
    second = _pool().submit(kern["phase_local"], rate[half:], mean, out[half:], ends)
    carry = first.result()
    second.result()
    chain = np.empty(tail_blocks + 1)
    chain[0] = carry
    chain[1:] = ends
    np.add.accumulate(chain, out=chain)  # C_b of each block of the second half
    split = tail_blocks // 2
    cut = half + split * PHASE_BLOCK
    jobs = [_pool().submit(kern["phase_fix"], out[half:cut], chain[:split], dt),
            _pool().submit(kern["phase_fix"], out[cut:], chain[split:tail_blocks], dt)]
    for job in jobs:
        job.result()


def sum_overlapping(source: PhaseSource, ms: I64, totals_n: I64, order: int) -> F64:
    """Blocked sums of squared differences of order 2 or 3 over positions i < totals_n[t].

    With the numba kernels (which release the GIL) the τ values are shared between threads;
    each τ's sum is still computed by one thread in the same order, so the results are the same
    bit for bit whatever the thread count.
    """
    kern = get_kernels()["sumsq_overlap"]
    offsets, win = _windows(ms, order)
    totals = np.zeros(ms.size)
    groups = _job_groups(totals_n)
    if isinstance(source, ArrayPhase):  # one kernel call per thread over the whole array
        _run_groups(kern, source.array, offsets, win, totals_n.astype(np.int64), order, totals,
                    groups)
        return totals
    for buf, starts, n_t in _superblocks(source, offsets, win, totals_n, order):
        _run_groups(kern, buf, starts, win, n_t, order, totals, groups)
    return totals


def sum_overlapping_rows(phases: F64, ms: I64, totals_n: I64, order: int) -> F64:
    """:func:`sum_overlapping` of every row of `phases` (k, n) in one kernel pass; (k, len(ms)).

    The rows form one buffer; job (j, t) is τ_t of row j with its windows moved on by j·n. The
    jobs of different rows never chain (their first windows differ), so each sum is formed by
    the same operations as :func:`sum_overlapping` of its row alone: equal bit for bit, for
    the set-up cost (windows, thread groups, kernel call) of one row.
    """
    kern = get_kernels()["sumsq_overlap"]
    k, n = phases.shape
    offsets, win = _windows(ms, order)
    rows = np.arange(k, dtype=np.int64)
    starts = (offsets[None, :] + n * rows[:, None]).reshape(-1)
    wins = np.ascontiguousarray(
        (win[None, :, :] + offsets.size * rows[:, None, None]).reshape(-1, win.shape[1]))
    counts = np.tile(totals_n.astype(np.int64), k)
    totals = np.zeros(counts.size)
    _run_groups(kern, np.ascontiguousarray(phases).reshape(-1), starts, wins, counts, order,
                totals, _job_groups(counts))
    return totals.reshape(k, ms.size)


def _superblocks(source: PhaseSource, offsets: I64, win: I64, counts: I64,
                 order: int) -> Iterator[tuple[F64, I64, I64]]:
    """Per superblock of terms: the windows the live jobs need, their starts, each job's count.

    Jobs with no terms left in a superblock read nothing (their window starts are 0 and unused).
    """
    step = source.superblock
    for start in range(0, int(counts.max(initial=0)), step):
        n_t = np.clip(counts - start, 0, step).astype(np.int64)
        need = np.unique(win[n_t > 0, : order + 1])
        buf, starts = source.gather(start, offsets[need], step)
        full = np.zeros(offsets.size, dtype=np.int64)
        full[need] = starts
        yield buf, full, n_t


def _run_groups(kern: Callable[..., None], buf: F64, starts: I64, win: I64, n_t: I64,
                order: int, totals: F64, groups: list[I64]) -> None:
    """One call of the overlapping-sum kernel per job group (on the pool when there are several).

    Each group works on a copy of its running sums, written back afterwards.
    """
    if len(groups) == 1:
        kern(buf, starts, win, n_t, order, totals)
        return
    parts = [totals[g] for g in groups]
    futures = [_pool().submit(kern, buf, starts, np.ascontiguousarray(win[g]),
                              np.ascontiguousarray(n_t[g]), order, part)
               for g, part in zip(groups, parts, strict=True)]
    for f in futures:
        f.result()
    for g, part in zip(groups, parts, strict=True):
        totals[g] = part


def _sum_seq(source: PhaseSource, ms: I64, totals_n: I64, order: int, power: int,
             acc: F64 | None = None) -> F64:
    kern = get_kernels()["sum_seq"]
    offsets, win = _windows(ms, order)
    acc = np.zeros(ms.size) if acc is None else acc
    for buf, starts, n_t in _superblocks(source, offsets, win, totals_n, order):
        kern(buf, starts, win, n_t, order, power, acc)
    return acc


def sum_nonoverlapping(source: PhaseSource, ms: I64, order: int) -> F64:
    """Sequential Σ d² of the non-overlapping (stride m) estimator: the decimated series x[::m]."""
    kern = get_kernels()["sum_seq"]
    out = np.zeros(ms.size)
    one = np.array([0, 1, 2, 3], dtype=np.int64)
    win = one[None, :].copy()
    n = source.n_phase
    step = source.superblock
    for t, m in enumerate(ms.tolist()):
        n_dec = -(-n // m)  # len(x[::m])
        n_t = n_dec - order
        acc = np.zeros(1)
        for start in range(0, max(n_t, 0), step):
            cnt = min(step, n_t - start)
            z = source.read(start * m, min(n, (start + cnt + order) * m), m)
            kern(z, one, win, np.array([cnt], dtype=np.int64), order, 2, acc)
        out[t] = acc[0]
    return out


def sums_mdev(source: PhaseSource, ms: I64) -> F64:
    """Σ_j v_j² of the modified Allan variance, v_j the sums of m second differences.

    v_0 is a sequential sum of the first m second differences; then v_{j+1} = v_j + t_j with
    t_j the third difference at j, as in NIST SP 1065 eq. (14) (the recursion of Stable32's and
    allantools' implementations).
    """
    ms = ms.astype(np.int64)
    v0 = _sum_seq(source, ms, ms.copy(), 2, 1)
    totals = v0 * v0
    v = v0.copy()
    kern = get_kernels()["mdev_running"]
    offsets, win = _windows(ms, 3)
    n_steps = np.maximum(source.n_phase - 3 * ms, 0).astype(np.int64)
    for buf, starts, n_t in _superblocks(source, offsets, win, n_steps, 3):
        kern(buf, starts, win, n_t, v, totals)
    return totals


def read_reflected(source: PhaseSource, start: int, stop: int) -> F64:
    """x*[start:stop] of the reflected extension (module docstring), for −(n−2) ≤ start."""
    n = source.n_phase
    lo, hi = max(start, 0), min(stop, n)
    parts: list[F64] = []
    if start < 0:
        x0 = source.read(0, 1)[0]
        left = source.read(1, -start + 1)[::-1]  # x[-start] … x[1]
        parts.append(2.0 * x0 - left[: min(stop, 0) - start])
    if hi > lo:
        parts.append(source.read(lo, hi))
    if stop > n:
        xl = source.read(n - 1, n)[0]
        a, b = max(start, n), stop  # x*[n-1+j] = 2x[n-1] − x[n-1-j], j = a-n+1 … b-n
        right = source.read(2 * (n - 1) - (b - 1), 2 * (n - 1) - a + 1)[::-1]
        parts.append(2.0 * xl - right)
    if not parts:
        return np.empty(0)
    return np.ascontiguousarray(np.concatenate(parts))


def sums_totdev(source: PhaseSource, ms: I64) -> F64:
    """Σ_{i=1}^{n−2} (x*[i−m] − 2x*[i] + x*[i+m])² (NIST SP 1065 eq. (25)), blocked sums."""
    kern = get_kernels()["sumsq_overlap"]
    n = source.n_phase
    totals = np.zeros(ms.size)
    win = np.array([[0, 1, 2, 0]], dtype=np.int64)
    step = source.superblock
    n_centres = n - 2
    for t, m in enumerate(ms.tolist()):
        acc = np.zeros(1)
        for start in range(0, n_centres, step):
            cnt = min(step, n_centres - start)
            base = 1 + start - m  # x* index of the first window
            buf = np.concatenate([read_reflected(source, base + k * m, base + k * m + cnt)
                                  for k in range(3)])
            starts = np.array([0, cnt, 2 * cnt], dtype=np.int64)
            kern(buf, starts, win, np.array([cnt], dtype=np.int64), 2, acc)
        totals[t] = acc[0]
    return totals


def decimated_averages(source: PhaseSource, m: int, tau0_s: float, max_points: int) -> F64:
    """Up to `max_points` consecutive τ-averages of the rate, (x[(k+1)m] − x[km])/(m·τ0).

    They are taken from the middle of the record (noise identification, :mod:`..edf`).
    """
    n_avg = (source.n_phase - 1) // m
    k = min(n_avg, max_points)
    k0 = (n_avg - k) // 2
    x = source.read(k0 * m, (k0 + k) * m + 1, m)
    out: F64 = np.diff(x) / (m * tau0_s)
    return out
