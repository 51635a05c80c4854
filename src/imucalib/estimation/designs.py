"""Linear designs of the known-orientation triad calibration (docs/equations.md §10, §12).

Contents
--------
:class:`LinearDesign`
    A design matrix with its parameter names.
:func:`build_triad_design`
    Rows of y_k − x_k = b + M·x_k for K known inputs x_k (specific force or angular rate).
:data:`SIX_POSITION_UP_B`
    The six gravity directions of procedure P1, calibration step 1 (docs/p1.md), in the body frame
    (Z up, Z down, X up, X down, Y up, Y down).
:data:`TRIAD_PARAMETER_NAMES`
    ``bias_x, bias_y, bias_z, M_xx, M_xy, …, M_zz``.

Model
-----
The linear part of :class:`~imucalib.models.triad.TriadModel`, y = b + (I + M)·x + n, rearranged
as y_k − x_k = b + M·x_k: for input k and sensor axis i the row is [eᵢᵀ, x_kᵀ ⊗ eᵢᵀ], i.e.
the observation depends on bᵢ and on the i-th row of M (M_ij: sensor i, input axis j). Rows are
ordered by input, then axis (row 3k + i). For a static accelerometer position with the body axis
u_k up, x_k = g·u_k (a level IMU with z up reads +g on z, `imucalib.conventions`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.conventions import AXES

__all__ = ["SIX_POSITION_UP_B", "TRIAD_PARAMETER_NAMES", "LinearDesign", "build_triad_design"]

#: Parameter order of :func:`build_triad_design`.
TRIAD_PARAMETER_NAMES: tuple[str, ...] = (
    *(f"bias_{a}" for a in AXES),
    *(f"M_{i}{j}" for i in AXES for j in AXES),
)

#: Unit "up" vectors in b of the six P1 positions: Z up, Z down, X up, X down, Y up, Y down.
SIX_POSITION_UP_B: NDArray[np.float64] = np.array(
    [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0],
     [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]
)
SIX_POSITION_UP_B.setflags(write=False)


@dataclass(frozen=True, eq=False)
class LinearDesign:
    """A linear design: observations z = H·x + n.

    Attributes
    ----------
    H : ndarray, shape (m, p)
        Design matrix (read-only).
    param_names : tuple of str
        Column names.
    """

    H: NDArray[np.float64]
    param_names: tuple[str, ...]


def build_triad_design(input_b: ArrayLike) -> LinearDesign:
    """Build the 12-parameter triad design for K known inputs (module docstring).

    Parameters
    ----------
    input_b : array_like, shape (K, 3)
        Known true inputs in the body frame b: specific force [m/s²] or angular rate [rad/s].

    Returns
    -------
    LinearDesign
        H of shape (3K, 12), columns :data:`TRIAD_PARAMETER_NAMES`; the matching observations
        are (y_k − x_k) flattened in the same row order.

    Raises
    ------
    InvalidInputError
        If `input_b` is not a finite (K, 3) array.

    Examples
    --------
    >>> d = build_triad_design(9.8 * SIX_POSITION_UP_B)
    >>> d.H.shape, d.param_names[:4]
    ((18, 12), ('bias_x', 'bias_y', 'bias_z', 'M_xx'))
    """
    x = as_array(input_b, "input_b", shape=(None, 3))
    k = x.shape[0]
    H = np.zeros((3 * k, 12))
    for i in range(3):
        rows = slice(i, 3 * k, 3)
        H[rows, i] = 1.0
        H[rows, 3 + 3 * i: 6 + 3 * i] = x
    H.setflags(write=False)
    return LinearDesign(H=H, param_names=TRIAD_PARAMETER_NAMES)
