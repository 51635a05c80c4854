"""Column sums and block means of a long (n, k) window in one compiled pass each.

A long static record is reduced in blocks (:class:`~imucalib.procedures.common.windows.
RunningMoments`): per block, the sums Σ(xᵢ − s) of the raw rows and Σ(yᵢ − s), Σ(yᵢ − s)² of the
filtered rows about a shift s (the first block's mean, which keeps the sums well conditioned:
the variance is then (Σd² − (Σd)²/n)/(n − 1), Welford's "shifted data" form, Chan, Golub &
LeVeque, *Amer. Statist.* 37(3), 1983), and the means of consecutive groups of 2^j rows for the
Allan variance. numpy computes each with its own temporaries and passes, and a reduction along
the rows of an array only six columns wide costs about 2 ns an element; here:

- :func:`shifted_sums` makes the three sums in one pass over the two blocks;
- :func:`block_means` the group means in one pass;
- :func:`mean_rows` the mean of the rows, ``x.mean(axis=0)`` (the static detector's and the
  field calibration's interval means: numpy takes about 14 ns a row of a three-column
  array, the kernel about 3).

They add in numpy's order — a reduction along axis 0 of a C-ordered array of two columns or
more accumulates the rows one after the other, ``((x₀ + x₁) + x₂) + …``, and so does a mean
over the middle axis of ``x.reshape(-1, m, k)``, which then divides by m — so the results equal
numpy's bit for bit (``tests/processing/test_moments.py``). Without numba, for arrays that are
not C-ordered, and for one column (whose contiguous rows numpy sums pairwise), numpy computes
them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["block_means", "mean_rows", "shifted_sums"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernels": None, "error": None}


def _sums_loop(raw: _F64, filt: _F64, shift: _F64, out: _F64) -> None:  # pragma: no cover
    n, k = raw.shape
    for c in range(k):
        out[0, c] = raw[0, c] - shift[c]
        d = filt[0, c] - shift[c]
        out[1, c] = d
        out[2, c] = d * d
    for i in range(1, n):
        for c in range(k):
            out[0, c] += raw[i, c] - shift[c]
            d = filt[i, c] - shift[c]
            out[1, c] += d
            out[2, c] += d * d


def _means_loop(x: _F64, m: int, out: _F64) -> None:  # pragma: no cover
    groups, k = out.shape
    for g in range(groups):
        base = g * m
        for c in range(k):
            acc = x[base, c]
            for j in range(1, m):
                acc += x[base + j, c]
            out[g, c] = acc / m


def _mean_rows_loop(x: _F64, out: _F64) -> None:  # pragma: no cover
    n, k = x.shape
    if k == 3:
        # a triad: its three sums are independent chains kept in registers (through `out`
        # each addition waits on a store and a load); the same additions in the same order
        a0, a1, a2 = x[0, 0], x[0, 1], x[0, 2]
        for i in range(1, n):
            a0 += x[i, 0]
            a1 += x[i, 1]
            a2 += x[i, 2]
        out[0], out[1], out[2] = a0 / n, a1 / n, a2 / n
        return
    for c in range(k):
        out[c] = x[0, c]
    for i in range(1, n):
        row = x[i]
        for c in range(k):
            out[c] += row[c]
    for c in range(k):
        out[c] = out[c] / n


_Kernels = tuple[Callable[..., None], Callable[..., None], Callable[..., None]]


def _kernels() -> _Kernels | None:
    if _STATE["kernels"] is None and _STATE["error"] is None:
        try:
            import numba

            jit = numba.njit(cache=True, nogil=True)
            sums, means, rows = jit(_sums_loop), jit(_means_loop), jit(_mean_rows_loop)
            probe = np.ones((4, 2))
            sums(probe, probe, np.zeros(2), np.empty((3, 2)))  # compile (or load the cache)
            means(probe, 2, np.empty((2, 2)))
            rows(probe, np.empty(2))
            _STATE["kernels"] = (sums, means, rows)
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Kernels | None = _STATE["kernels"]
    return found


def _compiled(*arrays: _F64) -> _Kernels | None:
    # one column: numpy sums the contiguous rows pairwise, not one after the other
    ok = all(a.dtype == np.float64 and a.ndim == 2 and a.shape[1] >= 2 and a.flags.c_contiguous
             for a in arrays)
    return _kernels() if ok else None


def shifted_sums(raw: _F64, filtered: _F64, shift: _F64) -> tuple[_F64, _F64, _F64]:
    """Return Σ(raw − shift), Σ(filtered − shift) and Σ(filtered − shift)² over the rows.

    Parameters
    ----------
    raw, filtered : ndarray, shape (n, k), n ≥ 1
    shift : ndarray, shape (k,)

    Returns
    -------
    tuple of ndarray, each shape (k,)
        numpy's ``(raw - shift).sum(axis=0)``, ``d.sum(axis=0)`` and ``(d * d).sum(axis=0)``
        with d = filtered − shift, bit for bit (module docstring).
    """
    kernels = _compiled(raw, filtered) if raw.shape == filtered.shape and raw.shape[0] else None
    if kernels is None:
        d = filtered - shift
        return (raw - shift).sum(axis=0), d.sum(axis=0), (d * d).sum(axis=0)
    out = np.empty((3, raw.shape[1]))
    kernels[0](raw, filtered, np.ascontiguousarray(shift, dtype=np.float64), out)
    return out[0], out[1], out[2]


def block_means(x: _F64, m: int) -> _F64:
    """Return the means of consecutive groups of `m` rows (the last partial group left out).

    numpy's ``x[:g·m].reshape(g, m, k).mean(axis=1)``, g = ⌊n/m⌋, bit for bit.
    """
    groups = x.shape[0] // m
    kernels = _compiled(x) if groups else None
    if kernels is None:
        return np.asarray(x[:groups * m].reshape(-1, m, x.shape[1]).mean(axis=1),
                          dtype=np.float64)
    out = np.empty((groups, x.shape[1]))
    kernels[1](x, m, out)
    return out


def mean_rows(x: _F64) -> _F64:
    """Return the mean of the rows of `x` (n, k), n ≥ 1: ``x.mean(axis=0)`` bit for bit.

    numpy adds the rows of a C-ordered array of two columns or more one after the other and
    divides the sums by n (module docstring); the kernel does the same. One column (numpy then
    sums pairwise), other layouts and dtypes: numpy.
    """
    kernels = _compiled(x) if x.ndim == 2 and x.shape[0] else None
    if kernels is None:
        return np.asarray(x.mean(axis=0), dtype=np.float64)
    out = np.empty(x.shape[1])
    kernels[2](x, out)
    return out
