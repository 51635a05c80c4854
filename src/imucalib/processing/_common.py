"""Input checks shared by the processing package (private)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError

__all__ = ["as_columns", "as_time", "restore_shape"]


def as_columns(values: ArrayLike, name: str, *, min_samples: int = 1, copy: bool = True
               ) -> tuple[NDArray[np.float64], bool]:
    """Return `values` as a finite (n, k) float64 array and whether the input was 1-D.

    With ``copy=False`` a C-ordered float64 ndarray comes back as it is, for callers that only
    read it; the others get their own C-ordered copy to change (a copy's layout fixes the
    order of numpy's reductions, so results do not depend on the caller's layout).
    """
    if (not copy and isinstance(values, np.ndarray) and values.dtype == np.float64
            and values.flags.c_contiguous):
        arr = values
        if not np.all(np.isfinite(arr)):
            bad = int(arr.size - np.count_nonzero(np.isfinite(arr)))
            raise InvalidInputError(f"`{name}` must be finite; got {bad} NaN or infinite "
                                    "value(s)")
    else:
        arr = as_array(values, name)
    if arr.ndim not in (1, 2):
        raise InvalidInputError(f"`{name}` must have shape (n,) or (n, k); got {arr.shape}")
    one_d = arr.ndim == 1
    cols = arr[:, None] if one_d else arr
    if cols.shape[0] < min_samples or cols.shape[1] < 1:
        raise InvalidInputError(
            f"`{name}` must hold at least {min_samples} samples in at least one column; got shape "
            f"{arr.shape}"
        )
    return cols, one_d


def as_time(time_s: ArrayLike, name: str, n: int | None = None, *,
            strict: bool = True) -> NDArray[np.float64]:
    """Return a finite (n,) time vector, strictly (or weakly) increasing."""
    t = as_array(time_s, name)
    if t.ndim != 1:
        raise InvalidInputError(f"`{name}` must have shape (n,); got {t.shape}")
    if n is not None and t.size != n:
        raise InvalidInputError(f"`{name}` must have {n} samples (one per row); got {t.size}")
    d = np.diff(t)
    bad = d <= 0 if strict else d < 0
    if bad.any():
        i = int(np.argmax(bad))
        rule = "strictly increasing" if strict else "non-decreasing"
        raise InvalidInputError(
            f"`{name}` must be {rule}; got {name}[{i + 1}] = {float(t[i + 1])!r} after "
            f"{name}[{i}] = {float(t[i])!r} ({int(bad.sum())} such step(s))"
        )
    return t


def restore_shape(cols: NDArray[np.float64], one_d: bool) -> NDArray[np.float64]:
    """Undo :func:`as_columns` for a 1-D input."""
    return cols[:, 0] if one_d else cols
