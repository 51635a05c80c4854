"""The running median of a sample's 2h neighbours: one sorted window slid along the column.

:func:`neighbour_median` returns, for each i in [h, n − h), the median of the 2h samples
x_{i−h} … x_{i+h} *without* x_i: the mean of their order statistics h − 1 and h (0-based).

It keeps the 2h + 1 samples of the window sorted; moving one sample on removes the outgoing
value and inserts the incoming one (O(h) shifts), so a column of n samples costs O(n·h) instead
of the O(n·h) *per-window copy and partition* of a ``sliding_window_view`` with
``np.partition`` (and its n × 2h temporary). With x_i at position p of the sorted window, the
neighbours' order statistic j is the window's j for j < p and the window's j + 1 otherwise; ties
with x_i give the same values whichever of the equal positions p is, so the result equals the
partition's bit for bit (the same two numbers, averaged the same way). This is the
"double-ended sorted list" running median of Härdle & Steiger (1995, "Optimal median smoothing",
Applied Statistics 44(2):258–264) in its simplest form, which is the fastest for the small h the
outlier rule uses (h = 4).

For h = 4, the outlier rule's default, the 8 neighbours go through a 19-comparator sorting
network instead (branch-free min/max, two samples side by side in vector registers: about
0.8 ns a sample against 4 for one sample at a time, 23 for the sorted window and 107 for the
partition on the project's 2-core machine, ``bench/bench_analysis.py --kernels``).
The numba kernels are compiled on first use (cached on disk); without numba the numpy path of
:func:`_neighbour_median_np` gives the same values.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

__all__ = ["neighbour_median"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernel": None, "error": None}


def _neighbour_median_loop(x: _F64, h: int, out: _F64) -> None:  # pragma: no cover - numba
    """Fill ``out[h:n-h]`` with the median of each sample's 2h neighbours (module docstring).

    Positions are found by counting (branch-free loops over the 2h + 1 values, faster than a
    binary search for the small windows of the outlier rule).
    """
    n = x.size
    w = 2 * h + 1
    win = np.sort(x[:w])
    for i in range(h, n - h):
        if i > h:
            old = x[i - h - 1]
            new = x[i + h]
            k = 0  # first position of `old`
            for j in range(w):
                k += win[j] < old
            if new >= old:
                while k + 1 < w and win[k + 1] < new:
                    win[k] = win[k + 1]
                    k += 1
            else:
                while k > 0 and win[k - 1] > new:
                    win[k] = win[k - 1]
                    k -= 1
            win[k] = new
        xi = x[i]
        p = 0  # a position of x_i: the values below it
        for j in range(w):
            p += win[j] < xi
        a = win[h - 1] if h - 1 < p else win[h]
        b = win[h] if h < p else win[h + 1]
        out[i] = 0.5 * (a + b)


#: Batcher-style 19-comparator sorting network of 8 values (Knuth, TAOCP vol. 3 §5.3.4, Fig. 49;
#: checked on all 2⁸ binary inputs by the 0-1 principle in tests/processing/test_median_kernel.py)
NETWORK_8 = ((0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7), (0, 1), (2, 3),
             (4, 5), (6, 7), (2, 4), (3, 5), (1, 4), (3, 6), (1, 2), (3, 4), (5, 6))


def _median8_loop(x: _F64, out: _F64) -> None:  # pragma: no cover - numba
    """With h = 4, sort each sample's 8 neighbours with :data:`NETWORK_8` (branch-free min/max).

    Two neighbouring samples i (values a) and i + 1 (values b) go through the network side by
    side, comparator for comparator: the compiler packs each pair of identical operations on
    adjacent data into one vector instruction (about 0.8 ns a sample against 4 for one sample
    at a time; the loop must keep this form: others tried were not vectorised). A comparator
    is ``(u if u < v else v), (v if u < v else u)``, the min/max that vectorises; with a tie
    both are the same value. An odd count leaves one sample, whose 8 neighbours are sorted.
    """
    n = x.size
    i = 4
    while i + 2 <= n - 4:
        a0, a1, a2, a3 = x[i - 4], x[i - 3], x[i - 2], x[i - 1]
        a4, a5, a6, a7 = x[i + 1], x[i + 2], x[i + 3], x[i + 4]
        b0, b1, b2, b3 = x[i - 3], x[i - 2], x[i - 1], x[i]
        b4, b5, b6, b7 = x[i + 2], x[i + 3], x[i + 4], x[i + 5]
        a0, a2 = (a0 if a0 < a2 else a2), (a2 if a0 < a2 else a0)
        b0, b2 = (b0 if b0 < b2 else b2), (b2 if b0 < b2 else b0)
        a1, a3 = (a1 if a1 < a3 else a3), (a3 if a1 < a3 else a1)
        b1, b3 = (b1 if b1 < b3 else b3), (b3 if b1 < b3 else b1)
        a4, a6 = (a4 if a4 < a6 else a6), (a6 if a4 < a6 else a4)
        b4, b6 = (b4 if b4 < b6 else b6), (b6 if b4 < b6 else b4)
        a5, a7 = (a5 if a5 < a7 else a7), (a7 if a5 < a7 else a5)
        b5, b7 = (b5 if b5 < b7 else b7), (b7 if b5 < b7 else b5)
        a0, a4 = (a0 if a0 < a4 else a4), (a4 if a0 < a4 else a0)
        b0, b4 = (b0 if b0 < b4 else b4), (b4 if b0 < b4 else b0)
        a1, a5 = (a1 if a1 < a5 else a5), (a5 if a1 < a5 else a1)
        b1, b5 = (b1 if b1 < b5 else b5), (b5 if b1 < b5 else b1)
        a2, a6 = (a2 if a2 < a6 else a6), (a6 if a2 < a6 else a2)
        b2, b6 = (b2 if b2 < b6 else b6), (b6 if b2 < b6 else b2)
        a3, a7 = (a3 if a3 < a7 else a7), (a7 if a3 < a7 else a3)
        b3, b7 = (b3 if b3 < b7 else b7), (b7 if b3 < b7 else b3)
        a0, a1 = (a0 if a0 < a1 else a1), (a1 if a0 < a1 else a0)
        b0, b1 = (b0 if b0 < b1 else b1), (b1 if b0 < b1 else b0)
        a2, a3 = (a2 if a2 < a3 else a3), (a3 if a2 < a3 else a2)
        b2, b3 = (b2 if b2 < b3 else b3), (b3 if b2 < b3 else b2)
        a4, a5 = (a4 if a4 < a5 else a5), (a5 if a4 < a5 else a4)
        b4, b5 = (b4 if b4 < b5 else b5), (b5 if b4 < b5 else b4)
        a6, a7 = (a6 if a6 < a7 else a7), (a7 if a6 < a7 else a6)
        b6, b7 = (b6 if b6 < b7 else b7), (b7 if b6 < b7 else b6)
        a2, a4 = (a2 if a2 < a4 else a4), (a4 if a2 < a4 else a2)
        b2, b4 = (b2 if b2 < b4 else b4), (b4 if b2 < b4 else b2)
        a3, a5 = (a3 if a3 < a5 else a5), (a5 if a3 < a5 else a3)
        b3, b5 = (b3 if b3 < b5 else b5), (b5 if b3 < b5 else b3)
        a1, a4 = (a1 if a1 < a4 else a4), (a4 if a1 < a4 else a1)
        b1, b4 = (b1 if b1 < b4 else b4), (b4 if b1 < b4 else b1)
        a3, a6 = (a3 if a3 < a6 else a6), (a6 if a3 < a6 else a3)
        b3, b6 = (b3 if b3 < b6 else b6), (b6 if b3 < b6 else b3)
        a1, a2 = (a1 if a1 < a2 else a2), (a2 if a1 < a2 else a1)
        b1, b2 = (b1 if b1 < b2 else b2), (b2 if b1 < b2 else b1)
        a3, a4 = (a3 if a3 < a4 else a4), (a4 if a3 < a4 else a3)
        b3, b4 = (b3 if b3 < b4 else b4), (b4 if b3 < b4 else b3)
        a5, a6 = (a5 if a5 < a6 else a6), (a6 if a5 < a6 else a5)
        b5, b6 = (b5 if b5 < b6 else b6), (b6 if b5 < b6 else b5)
        out[i] = 0.5 * (a3 + a4)
        out[i + 1] = 0.5 * (b3 + b4)
        i += 2
    if i < n - 4:
        nb = np.empty(8)
        for j in range(4):
            nb[j], nb[4 + j] = x[i - 4 + j], x[i + 1 + j]
        nb.sort()
        out[i] = 0.5 * (nb[3] + nb[4])


def _neighbour_median_np(x: _F64, h: int, out: _F64) -> None:
    """Compute the kernel's values by partitioning blocks of windows (bounded memory)."""
    n, w = x.size, 2 * h + 1
    step = 1 << 16
    for a in range(0, n - 2 * h, step):
        b = min(a + step, n - 2 * h)
        win = sliding_window_view(x[a:b + 2 * h], w)
        nb = np.delete(win, h, axis=1)  # the 2h neighbours, the sample itself left out
        nb.partition((h - 1, h), axis=1)
        out[a + h:b + h] = 0.5 * (nb[:, h - 1] + nb[:, h])


def _margin_loop(c: _F64, h: int, margin: _F64) -> None:  # pragma: no cover - numba
    """:func:`curvature_margin`'s arithmetic in one pass (the numpy path's operations)."""
    n = c.size
    for i in range(2 * h, n - 2 * h):
        margin[i] = abs(c[i - h] - 2.0 * c[i] + c[i + h]) / 4.0
    first = c[h] - 2.0 * c[2 * h] + c[3 * h]
    last = c[n - 3 * h - 1] - 2.0 * c[n - 2 * h - 1] + c[n - h - 1]
    for i in range(2 * h):
        margin[i] = abs(first) / 4.0
        margin[n - 2 * h + i] = abs(last) / 4.0
    start, end = (c[2 * h] - c[h]) / h, (c[n - 1 - h] - c[n - 1 - 2 * h]) / h
    for j in range(h):
        fi = float(j)
        c[j] = c[h] + start * (fi - h)
        c[n - h + j] = c[n - 1 - h] + end * (fi + 1.0)
        edge = (h - fi) * (2 * h - fi) / (2.0 * h * h)
        margin[j] = max(margin[j], abs(first) * edge)
        back = n - 1 - j  # the end's edge weights run backwards
        margin[back] = max(margin[back], abs(last) * edge)


_Kernels = tuple[Callable[[_F64, int, _F64], None], Callable[[_F64, _F64], None],
                 Callable[[_F64, int, _F64], None]]


def _kernels() -> _Kernels | None:
    if _STATE["kernel"] is None and _STATE["error"] is None:
        try:
            import numba

            jit = numba.njit(cache=True, nogil=True)
            general, eight = jit(_neighbour_median_loop), jit(_median8_loop)
            margins = jit(_margin_loop)
            probe = np.linspace(0.0, 1.0, 16)
            general(probe, 2, np.empty(16))  # compile (or load from the cache) now
            eight(probe, np.empty(16))
            margins(probe.copy(), 2, np.empty(16))
            _STATE["kernel"] = (general, eight, margins)
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernels | None = _STATE["kernel"]
    return found


def curvature_margin(c: _F64, h: int, *, backend: str = "auto") -> _F64:
    """Extrapolate the running median's edges in place and return the curvature margin.

    `c` (n ≥ 4h + 2) holds the medians of :func:`neighbour_median` for i in [h, n − h); the
    first and last h entries become the line through ĉ_h and ĉ_2h (at the end ĉ_{n−1−h} and
    ĉ_{n−1−2h}). The margin is |Δ²ᵢ|/4 with Δ²ᵢ = ĉ_{i−h} − 2ĉᵢ + ĉ_{i+h} inside, the nearest
    inner Δ² within 2h of either end, and on the i-th edge sample at least
    |Δ²|·(h − i)(2h − i)/(2h²) (:func:`imucalib.processing.outliers.reject_outliers_robust`'s
    rule). The numba kernel does in one pass what numpy does in about ten; the same values.
    """
    kernels = None if backend == "numpy" else _kernels()
    n = c.size
    margin = np.empty(n)
    if kernels is not None:
        kernels[2](c, h, margin)
        return margin
    d2 = np.zeros(n)
    d2[2 * h:n - 2 * h] = c[h:n - 3 * h] - 2.0 * c[2 * h:n - 2 * h] + c[3 * h:n - h]
    d2[:2 * h], d2[n - 2 * h:] = d2[2 * h], d2[n - 2 * h - 1]
    margin[:] = np.abs(d2) / 4.0
    i = np.arange(h, dtype=np.float64)
    slope = (c[2 * h] - c[h]) / h
    c[:h] = c[h] + slope * (i - h)
    slope = (c[n - 1 - h] - c[n - 1 - 2 * h]) / h
    c[n - h:] = c[n - 1 - h] + slope * (i + 1)
    edge = (h - i) * (2 * h - i) / (2.0 * h * h)  # at distance h − i before ĉ_h
    margin[:h] = np.maximum(margin[:h], np.abs(d2[:h]) * edge)
    margin[n - h:] = np.maximum(margin[n - h:], np.abs(d2[n - h:]) * edge[::-1])
    return margin


def neighbour_median(x: _F64, h: int, *, backend: str = "auto") -> _F64:
    """Return the median of each sample's 2h neighbours (itself left out) for i in [h, n − h).

    Parameters
    ----------
    x : ndarray, shape (n,)
        A finite column, n ≥ 2h + 1. [any unit]
    h : int
        Half-width, ≥ 1.
    backend : {"auto", "numba", "numpy"}
        ``"auto"`` uses the numba kernel when it compiles, else numpy (same values).

    Returns
    -------
    ndarray, shape (n,)
        Entries h … n − h − 1 hold the medians; the first and last h are left as zeros for the
        caller's edge rule. [unit of x]
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    out = np.zeros(x.size)
    kernels = None if backend == "numpy" else _kernels()
    if kernels is None:
        _neighbour_median_np(x, h, out)
    elif h == 4:
        kernels[1](x, out)
    else:
        kernels[0](x, h, out)
    return out
