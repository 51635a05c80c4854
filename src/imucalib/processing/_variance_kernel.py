"""The detectors' centred moving variance of every column in one compiled pass.

The static detector (:mod:`.static_detector`, ς = ‖(var_w of each column)‖) and the
segmentation (:mod:`.segmentation`, ζ = Σ_columns var_w, with the windowed mean) take the
variance of each window of w samples block-wise, so that it stays exact at any rate
(:func:`~.segmentation._window_moments`): the windows starting in block b (samples
b·w … b·w + w − 1) are summed over blocks b and b + 1 after subtracting block b's mean r_b,

    p_i = x_{b·w+i} − r_b,   C1_0 = 0,  C1_{i+1} = C1_i + p_i,   C2 likewise with p_i²,    (1)
    s1_j = (C1_{w+j} − C1_j)/w,   s2_j = (C2_{w+j} − C2_j)/w,   var_j = max(s2_j − s1_j², 0),

for the window starting at b·w + j (samples past the record's end repeat its last one; they
only feed windows past the end, which are discarded). numpy builds each block pair, both
cumulative sums and every difference as arrays of their own, one column at a time (the static
detector's six columns: 80 % of a field calibration's per-sample cost, docs/performance.md);
here one pass per block does all columns, with two scratch buffers of 2w + 1 values, and writes
only the per-sample output: each sample takes the value of its centred window, clipped at the
record's ends (window start max(0, min(i − ⌊w/2⌋, n − w))).

The block means r_b are numpy's (the caller's ``mean(axis=1)`` over the same (blocks, w, k)
shape as :func:`~.segmentation._window_moments`, so the same summation: pairwise for one
column, row after row for several), and Eq. (1) runs in numpy's order — ``cumsum`` adds
sequentially from p₀, the columns' sum starts from 0 and adds them in order — so the results
equal the numpy path's bit for bit (``tests/processing/test_variance_kernel.py``). The kernel
is compiled with numba on first use (cached on disk); without numba :func:`kernel` returns None
and the callers take the numpy path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["NORM", "SUM", "kernel", "moving_variance"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernel": None, "error": None}
#: Modes of :func:`moving_variance`: ‖(var_c)‖ (the static detector) or Σ var_c with the mean.
NORM, SUM = 0, 1


def _cumulate3(x: _F64, ref: _F64, b: int, w: int, c1: _F64,
               c2: _F64) -> None:  # pragma: no cover - numba
    """C1 and C2 of Eq. (1) for block b of three columns, into ``c1[c]``, ``c2[c]`` (2w + 1).

    The three columns' six running sums are independent chains of additions, kept in
    registers and advanced together (one column at a time waits on each addition's latency).
    """
    n = x.shape[0]
    base = b * w
    r0, r1, r2 = ref[b, 0], ref[b, 1], ref[b, 2]
    a0, a1, a2 = x[base, 0] - r0, x[base, 1] - r1, x[base, 2] - r2  # cumsum starts from p₀
    q0, q1, q2 = a0 * a0, a1 * a1, a2 * a2
    for c in range(3):
        c1[c, 0] = 0.0
        c2[c, 0] = 0.0
    c1[0, 1], c1[1, 1], c1[2, 1] = a0, a1, a2
    c2[0, 1], c2[1, 1], c2[2, 1] = q0, q1, q2
    for i in range(1, 2 * w):
        row = min(base + i, n - 1)  # past the record's end: its last sample
        p0, p1, p2 = x[row, 0] - r0, x[row, 1] - r1, x[row, 2] - r2
        a0 += p0
        a1 += p1
        a2 += p2
        q0 += p0 * p0
        q1 += p1 * p1
        q2 += p2 * p2
        c1[0, i + 1], c1[1, i + 1], c1[2, i + 1] = a0, a1, a2
        c2[0, i + 1], c2[1, i + 1], c2[2, i + 1] = q0, q1, q2


def _cumulate(x: _F64, ref: _F64, b: int, w: int, c1: _F64,
              c2: _F64) -> None:  # pragma: no cover - numba
    """C1 and C2 of Eq. (1) for block b, one column after the other (any number of columns)."""
    n, k = x.shape
    base = b * w
    for c in range(k):
        r = ref[b, c]
        a1 = x[base, c] - r  # cumsum starts from p₀
        a2 = a1 * a1
        c1[c, 0] = 0.0
        c2[c, 0] = 0.0
        c1[c, 1] = a1
        c2[c, 1] = a2
        for i in range(1, 2 * w):
            p = x[min(base + i, n - 1), c] - r  # past the record's end: its last sample
            a1 += p
            a2 += p * p
            c1[c, i + 1] = a1
            c2[c, i + 1] = a2


def _moving_variance_loop(x: _F64, ref: _F64, w: int, mode: int, out: _F64,
                          mean: _F64) -> None:  # pragma: no cover - numba
    """Eq. (1) for every block and column; write each sample's value (module docstring).

    mode NORM: ``out[i] = sqrt(Σ_c var_c²)``; mode SUM: ``out[i] = Σ_c var_c`` and
    ``mean[i, c] = r_b + s1`` (the windowed mean). Sums over the columns start from 0.
    """
    n, k = x.shape
    n_start = n - w + 1
    h = w // 2
    c1 = np.empty((k, 2 * w + 1))
    c2 = np.empty((k, 2 * w + 1))
    acc = np.empty(w)
    for b in range(ref.shape[0]):
        if k == 3:
            _cumulate3(x, ref, b, w, c1, c2)
        else:
            _cumulate(x, ref, b, w, c1, c2)
        base = b * w
        m = min(w, n_start - base)  # windows starting in this block
        acc[:m] = 0.0
        for c in range(k):
            for j in range(m):
                s1 = (c1[c, w + j] - c1[c, j]) / w
                s2 = (c2[c, w + j] - c2[c, j]) / w
                v = s2 - s1 * s1
                if v < 0.0:
                    v = 0.0
                if mode == NORM:
                    acc[j] = acc[j] + v * v
                else:
                    acc[j] = acc[j] + v
                    mean[base + j + h, c] = ref[b, c] + s1
        for j in range(m):
            out[base + j + h] = np.sqrt(acc[j]) if mode == NORM else acc[j]
    # the first h samples take window 0, the last w − 1 − h window n − w
    last = n_start - 1 + h
    for e in range(n - n_start):  # the samples outside h … last
        dst, src = (e, h) if e < h else (e + n_start, last)
        out[dst] = out[src]
        if mode != NORM:
            for c in range(k):
                mean[dst, c] = mean[src, c]


_Kernel = Callable[[_F64, _F64, int, int, _F64, _F64], None]


def kernel() -> _Kernel | None:
    """Return the compiled loop, or None without numba (the callers' numpy path)."""
    if _STATE["kernel"] is None and _STATE["error"] is None:
        try:
            import numba

            jit = numba.njit(cache=True, nogil=True)
            # the helpers are bound compiled in this namespace, where the compiled loop looks
            # them up
            g = _moving_variance_loop.__globals__
            g["_cumulate3"] = jit(_cumulate3)
            g["_cumulate"] = jit(_cumulate)
            loop = jit(_moving_variance_loop)
            probe = np.linspace(0.0, 1.0, 16).reshape(8, 2)
            for mode in (NORM, SUM):  # compile (or load from the cache) now
                loop(probe, np.zeros((2, 2)), 3, mode, np.empty(8), np.empty((8, 2)))
                loop(probe[:, :1], np.zeros((2, 1)), 3, mode, np.empty(8), np.empty((8, 1)))
            _STATE["kernel"] = loop
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernel | None = _STATE["kernel"]
    return found


def moving_variance(x: _F64, ref: _F64, w: int, mode: int) -> tuple[_F64, _F64 | None]:
    """Return each sample's moving-variance statistic (module docstring, Eq. (1)); compiled.

    Parameters
    ----------
    x : ndarray, shape (n, k), float64, n ≥ w
        The columns (any strides).
    ref : ndarray, shape (⌈(n − w + 1)/w⌉, k)
        The block means r_b: numpy's mean of rows b·w … b·w + w − 1, per block.
    w : int
        Window length, ≥ 1.
    mode : {NORM, SUM}
        NORM: ‖(var_c)‖ (:func:`~.static_detector._variance_norm`); SUM: Σ_c var_c and the
        windowed mean (:func:`~.segmentation._moving_mean_and_unsteadiness`).

    Returns
    -------
    out : ndarray, shape (n,)
    mean : ndarray, shape (n, k), or None
        The windowed mean (mode SUM).

    Requires :func:`kernel`.
    """
    loop = kernel()
    assert loop is not None
    n, k = x.shape
    if not 1 <= w <= n or ref.shape != (-(-(n - w + 1) // w), k):
        raise ValueError(f"need 1 ≤ w ≤ n and ref of shape (⌈(n − w + 1)/w⌉, k); got n = {n}, "
                         f"w = {w}, ref {ref.shape}")
    out = np.empty(n)
    mean = np.empty((n, k)) if mode == SUM else np.empty((0, k))
    loop(x, np.ascontiguousarray(ref, dtype=np.float64), w, mode, out, mean)
    return out, (mean if mode == SUM else None)
