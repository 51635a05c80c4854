"""Small input validators shared by the package (private).

Each returns a float64 copy of the input and raises :class:`~imucalib.errors.InvalidInputError`
with a message naming the argument, what was expected and what was received.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.errors import InvalidInputError

__all__ = [
    "as_array",
    "as_matrix33",
    "as_samples3",
    "as_vector3",
    "check_finite_scalar",
    "check_nonnegative",
    "check_positive",
]


def as_array(value: ArrayLike, name: str, *, shape: tuple[int | None, ...] | None = None,
             allow_nan: bool = False) -> NDArray[np.float64]:
    """Return `value` as a float64 array, checking its shape and finiteness.

    `shape` may contain ``None`` for a free dimension.
    """
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`{name}` must be numeric; got {type(value).__name__}") from exc
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            want is None or want == got for want, got in zip(shape, arr.shape, strict=False)
        )
        if not ok:
            want_txt = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
            raise InvalidInputError(f"`{name}` must have shape {want_txt}; got {arr.shape}")
    if not allow_nan and not np.isfinite(arr).all():
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise InvalidInputError(f"`{name}` must be finite; got {bad} NaN or infinite value(s)")
    return arr


def as_vector3(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return a finite float64 vector of shape (3,); a scalar is broadcast to three axes."""
    arr = np.array(value, dtype=np.float64) if np.isscalar(value) else value
    if np.ndim(arr) == 0:
        arr = np.full(3, float(np.asarray(arr)))
    return as_array(arr, name, shape=(3,))


def as_matrix33(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return a finite float64 matrix of shape (3, 3)."""
    return as_array(value, name, shape=(3, 3))


def as_samples3(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return finite float64 samples of shape (n, 3)."""
    return as_array(value, name, shape=(None, 3))


def check_finite_scalar(value: Any, name: str) -> float:
    """Return `value` as a finite float."""
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`{name}` must be a number; got {value!r}") from exc
    if not math.isfinite(out):
        raise InvalidInputError(f"`{name}` must be finite; got {out}")
    return out


def check_nonnegative(value: Any, name: str) -> float:
    """Return `value` as a finite float ≥ 0."""
    out = check_finite_scalar(value, name)
    if out < 0:
        raise InvalidInputError(f"`{name}` must be ≥ 0; got {out}")
    return out


def check_positive(value: Any, name: str) -> float:
    """Return `value` as a finite float > 0."""
    out = check_finite_scalar(value, name)
    if out <= 0:
        raise InvalidInputError(f"`{name}` must be > 0; got {out}")
    return out
