"""The robust outlier rule's passes after the running median, compiled: residuals and flags.

:func:`imucalib.processing.outliers.reject_outliers_robust` reduces each column in passes: the
running median ĉ (:mod:`._median_kernel`), its edges extrapolated and the curvature margin mᵢ,
the residuals rᵢ = xᵢ − ĉᵢ, their median and MAD (:mod:`._select_kernel`), and the flags
|rᵢ − med r| > k·s + mᵢ (Eq. (2) of :mod:`.outliers`). numpy makes the margin, the residuals,
the deviations, the thresholds and the flags each an array of its own, and counts the flags
along the rows of the (n, k) mask. Here two passes make them:

- :func:`residuals`: extrapolates ĉ's first and last h entries (the line through ĉ_h and ĉ_2h,
  at the end ĉ_{n−1−h} and ĉ_{n−1−2h}) and returns r = x − ĉ;
- :func:`flag_far`: computes each sample's margin from ĉ as it goes (|Δ²ᵢ|/4 inside, the edge
  rule within 2h of either end), writes the flags and returns their count.

The operations are :func:`~._median_kernel.curvature_margin`'s and the rule's numpy path's, in
the same order, so the flags equal numpy's bit for bit
(``tests/processing/test_flag_kernel.py``). The kernels are compiled with numba on first use
(cached on disk); without numba :func:`kernels` returns None and the caller takes the numpy
path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["flag_far", "kernels", "residuals"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernels": None, "error": None}


def _residual_loop(x: _F64, c: _F64, h: int, r: _F64) -> None:  # pragma: no cover - numba
    """Extrapolate ĉ's edges in place (curvature_margin's line), then r = x − ĉ."""
    n = c.size
    start, end = (c[2 * h] - c[h]) / h, (c[n - 1 - h] - c[n - 1 - 2 * h]) / h
    for j in range(h):
        fi = float(j)
        c[j] = c[h] + start * (fi - h)
        c[n - h + j] = c[n - 1 - h] + end * (fi + 1.0)
    for i in range(n):
        r[i] = x[i] - c[i]


def _flag_loop(r: _F64, c: _F64, h: int, center: float, threshold: float,
               flags: NDArray[np.bool_]) -> int:  # pragma: no cover - numba
    """Set flags = |r − center| > threshold + margin (the margin from ĉ as it goes); count them.

    The inner samples run over views from index 0 (indices the compiler knows are not
    negative: the loop vectorises), the 2h samples at either end one by one.
    """
    n = c.size
    first = abs(c[h] - 2.0 * c[2 * h] + c[3 * h])
    last = abs(c[n - 3 * h - 1] - 2.0 * c[n - 2 * h - 1] + c[n - h - 1])
    count = 0
    for i in range(2 * h):
        fi = float(i)
        edge = (h - fi) * (2 * h - fi) / (2.0 * h * h)
        m = first / 4.0 if i >= h else max(first / 4.0, first * edge)
        far = abs(r[i] - center) > threshold + m
        flags[i] = far
        count += far
        m = last / 4.0 if i >= h else max(last / 4.0, last * edge)
        far = abs(r[n - 1 - i] - center) > threshold + m
        flags[n - 1 - i] = far
        count += far
    before, mid, after = c[h:n - 3 * h], c[2 * h:n - 2 * h], c[3 * h:n - h]
    inner, out = r[2 * h:n - 2 * h], flags[2 * h:n - 2 * h]
    for k in range(inner.size):
        m = abs(before[k] - 2.0 * mid[k] + after[k]) / 4.0
        far = abs(inner[k] - center) > threshold + m
        out[k] = far
        count += far
    return count


_Kernels = tuple[Callable[[_F64, _F64, int, _F64], None],
                 Callable[[_F64, _F64, int, float, float, NDArray[np.bool_]], int]]


def kernels() -> _Kernels | None:
    """Return the compiled (residual, flag) kernels, or None without numba (numpy path)."""
    if _STATE["kernels"] is None and _STATE["error"] is None:
        try:
            import numba

            jit = numba.njit(cache=True, nogil=True)
            resid, flag = jit(_residual_loop), jit(_flag_loop)
            probe = np.linspace(0.0, 1.0, 16)
            resid(probe, probe.copy(), 2, np.empty(16))  # compile (or load from the cache) now
            flag(probe, probe, 2, 0.0, 1.0, np.empty(16, dtype=np.bool_))
            _STATE["kernels"] = (resid, flag)
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernels | None = _STATE["kernels"]
    return found


def residuals(x: _F64, c: _F64, h: int) -> _F64:
    """Extrapolate the running median's edges in place and return r = x − ĉ (compiled).

    `c` (n ≥ 4h + 2) holds :func:`~._median_kernel.neighbour_median`'s values for i in
    [h, n − h); `x` is the C-contiguous column. Requires :func:`kernels`.
    """
    found = kernels()
    assert found is not None
    r = np.empty(x.size)
    found[0](x, c, h, r)
    return r


def flag_far(r: _F64, c: _F64, h: int, center: float, threshold: float,
             out: NDArray[np.bool_]) -> int:
    """Write |rᵢ − center| > threshold + mᵢ into `out`; return how many (compiled).

    mᵢ is :func:`~._median_kernel.curvature_margin`'s margin of the extrapolated running
    median `c` (n ≥ 4h + 2). Requires :func:`kernels`.
    """
    found = kernels()
    assert found is not None
    return int(found[1](r, c, h, float(center), float(threshold), out))
