"""The static detector's rotation angles, θ = ∫(ω − b) dt over each gap, in one compiled call.

:func:`~imucalib.processing.static_detector.detect_for_thresholds` integrates the bias-free
rate over every gap between consecutive static intervals, for each of its threshold factors
(the automatic choice tries eight): by the trapezoid rule over the gap's samples a … b − 1,

    θ_c = Σ_{i=a}^{b−2} ½·((ω_{i+1,c} − b_c) + (ω_{i,c} − b_c))·(t_{i+1} − t_i).        (1)

numpy makes the differences, the sums, the products and the steps as arrays of their own for
each gap (about 50 ns a sample in five passes, plus some 20 µs of calls a gap); here one call
computes every gap of a detection. The operations are numpy's, in its order — the bias
subtracted first, ``0.5 * (r₁ + r₀)`` then times the step, and the column sums of a C-ordered
(m, 3) array added row after row from 0 (:mod:`.moments`, module docstring) — so the angles
equal the numpy path's bit for bit (``tests/processing/test_variance_kernel.py``). Compiled
with numba on first use (cached on disk); without numba :func:`kernel` returns None and the
detector takes the numpy path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["gap_angles", "kernel"]

_F64 = NDArray[np.float64]
_I64 = NDArray[np.int64]
_STATE: dict[str, Any] = {"kernel": None, "error": None}


def _angles_loop(t: _F64, rate: _F64, start: _I64, stop: _I64, bias: _F64,
                 out: _F64) -> None:  # pragma: no cover - numba
    """Eq. (1) for gap g over samples ``start[g] … stop[g] − 1``, into ``out[g]``."""
    k = rate.shape[1]
    for g in range(start.size):
        a, b = start[g], stop[g]
        for c in range(k):
            out[g, c] = 0.0
        for i in range(a, b - 1):
            step = t[i + 1] - t[i]
            for c in range(k):
                r0 = rate[i, c] - bias[g, c]
                r1 = rate[i + 1, c] - bias[g, c]
                out[g, c] = out[g, c] + 0.5 * (r1 + r0) * step


_Kernel = Callable[[_F64, _F64, _I64, _I64, _F64, _F64], None]


def kernel() -> _Kernel | None:
    """Return the compiled loop, or None without numba (the detector's numpy path)."""
    if _STATE["kernel"] is None and _STATE["error"] is None:
        try:
            import numba

            loop = numba.njit(cache=True, nogil=True)(_angles_loop)
            probe = np.linspace(0.0, 1.0, 8)
            idx = np.array([0, 4], dtype=np.int64)
            loop(probe, np.ones((8, 3)), idx, idx + 4, np.zeros((2, 3)), np.empty((2, 3)))
            _STATE["kernel"] = loop
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernel | None = _STATE["kernel"]
    return found


def gap_angles(t: _F64, rate: _F64, start: _I64, stop: _I64, bias: _F64) -> _F64:
    """Return θ of Eq. (1) for each gap (compiled; requires :func:`kernel`).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times. [s]
    rate : ndarray, shape (n, k)
        Gyro output. [rad/s]
    start, stop : ndarray of int64, shape (g,)
        Each gap's samples ``start … stop − 1`` (0 ≤ start, start + 2 ≤ stop ≤ n).
    bias : ndarray, shape (g, k)
        Each gap's bias b. [rad/s]

    Returns
    -------
    ndarray, shape (g, k)
        θ per gap. [rad]
    """
    loop = kernel()
    assert loop is not None
    out = np.empty((start.size, rate.shape[1]))
    loop(t, rate, start, stop, np.ascontiguousarray(bias, dtype=np.float64), out)
    return out
