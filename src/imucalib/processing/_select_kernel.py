"""An exact median of a float64 column by one bracketing pass: ``np.median``'s value, faster.

:func:`median` returns ``float(np.median(a))`` bit for bit for a 1-D float64 array, and
:func:`median_abs_deviation` returns ``float(np.median(np.abs(a - center)))`` without
materialising ``|a − center|``. The outlier rule (:func:`imucalib.processing.outliers.
reject_outliers_robust`) needs two such medians per window and column.

Algorithm (Floyd & Rivest, "Expected time bounds for selection", CACM 18(3):165–172, 1975):
the median's rank k is bracketed from a sorted pseudo-random sample of s = n^(2/3) values (a
fixed xorshift sequence of positions, so the result and the time are reproducible), by the
sample's order statistics [lo, hi] at ranks k·s/n ∓ 2√s (the sample count below the median has
a standard deviation of √s/2: the bracket misses with probability ≈ 6·10⁻⁵). One pass then
counts the values below, equal to and above lo and hi and copies those strictly between them,
≈ 4n/√s values, into a buffer (:func:`_bracket_loop`: blocks of 1024 values counted by a
vectorised loop, then compacted branch-free while in the cache). The order statistics are read
off the counts (ties with lo or hi, which quantised data produce in large numbers, cost
nothing) or selected in the buffer (Hoare's FIND with median-of-three pivots, sorting as the
guard against quadratic time). When the bracket misses, the buffer overflows or a NaN is seen,
:func:`numpy.median` answers instead, so the result is always numpy's. About 2 ns a value
against numpy's 7–12 for n from 10⁴ to 3·10⁶ (``bench/bench_analysis.py --kernels``; 3.4 ns
before the counting loop ran over views of its blocks, see :func:`_bracket_loop`).

numpy combines the middle order statistics as ``np.mean`` does: a pairwise sum that starts from
+0.0, divided by the count. For even n that is (0 + a + b)/2 whatever the association (0 + a = a
for a ≠ 0; a zero result is +0.0), for odd n 0 + a, so a −0.0 median comes out as +0.0 and a sum
that overflows as ±inf; :func:`_combine` does the same.

The kernel is compiled with numba on first use (cached on disk); without numba :func:`median`
calls :func:`numpy.median` (the same values).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["median", "median_abs_deviation"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernel": None, "error": None}
#: Below this many values the kernel selects in a copy of the whole array (no sample).
_SMALL = 256
#: Bracket half-width in units of √s (4 standard deviations √s/2 of the sample's count).
_WIDTH = 2.0
#: Values counted, then compacted, at a time by :func:`_bracket_loop` (8 KiB: in L1).
_BLOCK = 1024
_OK, _MISS = 0, 1

_Kernel = Callable[[_F64, float, bool], tuple[int, float, float]]


def _select_loop(buf: _F64, m: int, r: int) -> float:  # pragma: no cover - numba
    """Move the value of rank r (0-based) of ``buf[:m]`` to ``buf[r]``, smaller ones before it.

    Hoare's FIND with a median-of-three pivot; after 2·log₂(m) + 8 rounds without converging
    the remaining range is sorted (introselect's guard against quadratic time).
    """
    left, right = 0, m - 1
    budget = 8
    size = m
    while size > 1:
        budget += 2
        size >>= 1
    while right > left:
        if budget == 0:
            buf[left:right + 1] = np.sort(buf[left:right + 1])
            break
        budget -= 1
        mid = (left + right) >> 1
        a, b, c = buf[left], buf[mid], buf[right]
        if a > b:
            a, b = b, a
        if b > c:
            b = c
            if a > b:
                b = a
        pivot = b
        i, j = left, right
        while i <= j:
            while buf[i] < pivot:
                i += 1
            while buf[j] > pivot:
                j -= 1
            if i <= j:
                buf[i], buf[j] = buf[j], buf[i]
                i += 1
                j -= 1
        if r <= j:
            right = j
        elif r >= i:
            left = i
        else:
            break  # buf[j + 1 … i − 1] all equal the pivot: rank r is found
    return buf[r]


def _order_pair(buf: _F64, m: int, r: int) -> tuple[float, float]:  # pragma: no cover - numba
    """Values of ranks r and r + 1 of ``buf[:m]`` (the second NaN when r + 1 = m)."""
    first = _select_loop(buf, m, r)
    second = np.nan
    if r + 1 < m:
        second = buf[r + 1]
        for i in range(r + 2, m):
            if buf[i] < second:
                second = buf[i]
    return first, second



def _compact_block(blk: _F64, center: float, absdev: bool, lo: float, hi: float, buf: _F64,
                   m: int) -> int:  # pragma: no cover - numba
    """Store the values of `blk` strictly between lo and hi at ``buf[m:]``; return the new m.

    Branch-free: every value is stored at ``buf[m]`` and m grows by (v > lo) & (v < hi).
    """
    if absdev:
        for i in range(blk.size):
            v = abs(blk[i] - center)
            buf[m] = v
            m += (v > lo) & (v < hi)
    else:
        for i in range(blk.size):
            v = blk[i]
            buf[m] = v
            m += (v > lo) & (v < hi)
    return m


def _bracket_loop(a: _F64, center: float, absdev: bool, lo: float, hi: float, buf: _F64,
                  cap: int, counts: NDArray[np.int64]) -> None:  # pragma: no cover - numba
    """One pass: count the values below, at and above lo and hi, copy those strictly between.

    Blocks of :data:`_BLOCK` values are counted first (a vectorised loop that streams the
    block into the cache), then, when the block holds values inside, compacted
    (:func:`_compact_block`). The loops run over a view of the block from index 0: indexing
    ``a[i]`` over ``range(start, stop)`` instead keeps the compiler from vectorising the count
    (three times slower). `counts` receives m (−1 when more than `cap` values lie inside),
    #(v < lo), #(v ≤ lo), #(v < hi), #(v ≤ hi), #(v > hi); a NaN is in none of the last five.
    `buf` holds cap + 1 values.
    """
    n = a.size
    m = lt_lo = le_lo = lt_hi = le_hi = gt_hi = 0
    for start in range(0, n, _BLOCK):
        blk = a[start:start + _BLOCK]
        c_lt_lo = below = under = c_le_hi = c_gt_hi = 0
        for i in range(blk.size):
            v = abs(blk[i] - center) if absdev else blk[i]
            c_lt_lo += v < lo
            below += v <= lo
            under += v < hi
            c_le_hi += v <= hi
            c_gt_hi += v > hi
        lt_lo += c_lt_lo
        le_lo += below
        lt_hi += under
        le_hi += c_le_hi
        gt_hi += c_gt_hi
        if under > below:
            if m + under - below > cap:
                counts[0] = -1
                return
            m = _compact_block(blk, center, absdev, lo, hi, buf, m)
    counts[0], counts[1], counts[2] = m, lt_lo, le_lo
    counts[3], counts[4], counts[5] = lt_hi, le_hi, gt_hi


def _median_loop(a: _F64, center: float, absdev: bool
                 ) -> tuple[int, float, float]:  # pragma: no cover - numba
    """Order statistics ⌊(n−1)/2⌋ and ⌊n/2⌋ of a (or of |a − center| when `absdev`).

    Returns (status, low, high); status 1 when the bracket missed, the buffer overflowed or a
    value is NaN (the caller then asks numpy).
    """
    n = a.size
    k1 = (n - 1) // 2
    k2 = n // 2
    if n <= _SMALL:
        buf = np.empty(n)
        for i in range(n):
            v = abs(a[i] - center) if absdev else a[i]
            if v != v:
                return _MISS, 0.0, 0.0
            buf[i] = v
        low, high = _order_pair(buf, n, k1)
        return _OK, low, (low if k2 == k1 else high)
    # Floyd–Rivest sample: s ≈ n^(2/3) positions from a fixed xorshift sequence
    s = int(n ** (2.0 / 3.0))
    sample = np.empty(s)
    state = np.uint64(0x9E3779B97F4A7C15)
    for i in range(s):
        state ^= state << np.uint64(13)
        state ^= state >> np.uint64(7)
        state ^= state << np.uint64(17)
        j = int(state % np.uint64(n))
        sample[i] = abs(a[j] - center) if absdev else a[j]
    sample.sort()
    p = k1 * s / n
    d = int(_WIDTH * np.sqrt(s)) + 1
    ilo = max(int(p) - d, 0)
    ihi = min(int(p) + d + 1, s - 1)
    lo, hi = sample[ilo], sample[ihi]
    if lo != lo or hi != hi:
        return _MISS, 0.0, 0.0
    cap = min(n, 2 * ((ihi - ilo) * n) // s + 1024)
    buf = np.empty(cap + 1)
    counts = np.zeros(6, dtype=np.int64)
    _bracket_loop(a, center, absdev, lo, hi, buf, cap, counts)
    m, lt_lo, le_lo = int(counts[0]), int(counts[1]), int(counts[2])
    lt_hi, le_hi, gt_hi = int(counts[3]), int(counts[4]), int(counts[5])
    if m < 0:
        return _MISS, 0.0, 0.0  # the buffer overflowed
    if le_hi + gt_hi != n or k1 < lt_lo or k2 >= le_hi:
        return _MISS, 0.0, 0.0  # a NaN, or the median outside [lo, hi]
    # buffer ranks r and r + 1 cover k1 and k2 = k1 or k1 + 1 wherever they fall inside
    r = max(k1 - le_lo, 0)
    first = second = 0.0
    if m > 0 and le_lo <= k2 and k1 < lt_hi:
        first, second = _order_pair(buf, m, r)
    low = lo if k1 < le_lo else (hi if k1 >= lt_hi else (first if k1 - le_lo == r else second))
    high = lo if k2 < le_lo else (hi if k2 >= lt_hi else (first if k2 - le_lo == r else second))
    return _OK, low, high


def _combine(low: float, high: float, even: bool) -> float:
    """Combine the middle order statistics as numpy's ``mean`` does (module docstring)."""
    if even:
        return (0.0 + low + high) / 2.0
    return 0.0 + low


def _kernel() -> _Kernel | None:
    if _STATE["kernel"] is None and _STATE["error"] is None:
        try:
            import numba

            jit = numba.njit(cache=True, nogil=True)
            select = jit(_select_loop)
            pair = jit(_order_pair)
            # the helpers are bound compiled in this namespace, where the compiled
            # _median_loop looks them up
            g = _median_loop.__globals__
            g["_select_loop"], g["_order_pair"] = select, pair
            g["_compact_block"] = jit(_compact_block)
            g["_bracket_loop"] = jit(_bracket_loop)
            loop = jit(_median_loop)
            loop(np.linspace(0.0, 1.0, 16), 0.0, False)  # compile (or load from the cache)
            loop(np.linspace(0.0, 1.0, 16), 0.0, True)
            _STATE["kernel"] = loop
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernel | None = _STATE["kernel"]
    return found


def _run(a: _F64, center: float, absdev: bool, backend: str) -> float | None:
    """Return the kernel's median, or None when numpy must answer (no numba, a miss, NaN)."""
    kernel = None if backend == "numpy" or a.size == 0 else _kernel()
    if kernel is None:
        return None
    status, low, high = kernel(a, center, absdev)
    if status != _OK:
        return None
    return _combine(low, high, a.size % 2 == 0)


def median(a: NDArray[np.float64], *, backend: str = "auto") -> float:
    """Return ``float(np.median(a))`` bit for bit, by Floyd–Rivest selection (module docstring).

    Parameters
    ----------
    a : ndarray, shape (n,)
        Values; n ≥ 1. Not modified. [any unit]
    backend : {"auto", "numba", "numpy"}
        ``"auto"`` uses the numba kernel when it compiles, else :func:`numpy.median`.

    Returns
    -------
    float
        The median: the middle order statistic for odd n, the mean of the two middle ones
        (combined as numpy does) for even n. [unit of a]
    """
    x = np.ascontiguousarray(a, dtype=np.float64).reshape(-1)
    got = _run(x, 0.0, False, backend)
    return float(np.median(x)) if got is None else got


def median_abs_deviation(a: NDArray[np.float64], center: float, *,
                         backend: str = "auto") -> float:
    """Return ``float(np.median(np.abs(a - center)))`` bit for bit, without that temporary.

    The unscaled median absolute deviation about `center` (Rousseeuw & Croux, J. Amer.
    Statist. Assoc. 88(424), 1993), selected as in :func:`median`.

    Parameters
    ----------
    a : ndarray, shape (n,)
        Values; n ≥ 1. Not modified. [any unit]
    center : float
        The centre the deviations are taken from (usually the median of `a`). [unit of a]
    backend : {"auto", "numba", "numpy"}
        As for :func:`median`.

    Returns
    -------
    float
        The median of |aᵢ − center|. [unit of a]
    """
    x = np.ascontiguousarray(a, dtype=np.float64).reshape(-1)
    c = float(center)
    got = _run(x, c, True, backend)
    return float(np.median(np.abs(x - c))) if got is None else got
