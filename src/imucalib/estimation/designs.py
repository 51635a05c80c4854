"""The one builder of triad designs: rows per observation and model term (docs/equations.md §10).

Contents
--------
:class:`LinearDesign`
    A design matrix with its parameter names.
:func:`build_design`
    The design of z = y − x for K observations of a triad, with the model terms asked for
    (:data:`TRIAD_TERMS`: bias, scale/misalignment, K2, g-sensitivity, lever arm); every
    procedure's fit builds its design here (P1, P2, and the CRLB).
:func:`build_triad_design`
    Its 12-parameter case: rows of y_k − x_k = b + M·x_k for K known inputs x_k (specific force
    or angular rate).
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

Terms
-----
The linearised triad model of :class:`~imucalib.models.triad.TriadModel` (docs/p1.md, "Models
and estimation"), for K known inputs x_k with z_k = y_k − x_k:

    z_k = b + M·x_k + K2⊙(x_k⊙x_k) + G·f_k + [L_i·(ω̇_k×· + ω_k×(ω_k×·))]_i

Rows are ordered by observation, then sensor axis (row 3k + i), as in
:func:`build_triad_design`. The terms (:data:`TRIAD_TERMS`), each a block
of columns in the order asked for:

``"bias"``
    b_i: column i is 1 on sensor i's rows. Names ``bias_x`` … ``bias_z``.
``"scale_misalignment"``
    M_ij (sensor i, input axis j): x_k[j] on sensor i's rows. Names ``M_xx``, ``M_xy`` … ``M_zz``.
``"k2"``
    K2_i, the quadratic scale factor (small-M linearisation K2_i·u_i² ≈ K2_i·x_i²): x_k[i]² on
    sensor i's rows. Names ``K2_x`` … ``K2_z``.
``"g_sensitivity"``
    G_ij (gyro output i per specific force j): f_k[j] on sensor i's rows. Names ``G_xx`` …
    ``G_zz``. Needs `specific_force_b`.
``"lever_arm"``
    L_ij, component j of accelerometer i's position (the size effect: sensor i feels
    f + ω̇×r_i + ω×(ω×r_i)): row i of C_k = [ω̇_k]× + [ω_k]×² on sensor i's rows. Names
    ``L_xx`` … ``L_zz`` [m]. Needs `rate_b` (and `angular_accel_b`, zero when omitted).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError

__all__ = ["SIX_POSITION_UP_B", "TRIAD_PARAMETER_NAMES", "TRIAD_TERMS", "LinearDesign",
           "build_design", "build_triad_design"]

_F64 = NDArray[np.float64]

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
    return build_design(input_b, ("bias", "scale_misalignment"))


#: The model terms :func:`build_design` knows, in their usual order.
TRIAD_TERMS = ("bias", "scale_misalignment", "k2", "g_sensitivity", "lever_arm")


def _skew(v: _F64) -> _F64:
    """[v]×, the cross-product matrix: [v]×·r = v × r."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _per_sensor_rows(k: int, rows_k3: _F64) -> _F64:
    """Block (3K, 9): sensor i's rows carry rows_k3[k, i, :] in columns 3i … 3i + 2."""
    block = np.zeros((3 * k, 9))
    for i in range(3):
        block[i::3, 3 * i:3 * i + 3] = rows_k3[:, i, :]
    return block


def build_design(input_b: ArrayLike, terms: Sequence[str] = ("bias", "scale_misalignment"), *,
                 specific_force_b: ArrayLike | None = None, rate_b: ArrayLike | None = None,
                 angular_accel_b: ArrayLike | None = None) -> LinearDesign:
    """Build the design of z = y − x for K observations of a triad (module docstring).

    Parameters
    ----------
    input_b : array_like, shape (K, 3)
        The known true inputs x_k in the body frame: specific force [m/s²] for an
        accelerometer, angular rate [rad/s] for a gyro.
    terms : sequence of str
        Model terms of :data:`TRIAD_TERMS`, in the column order wanted.
    specific_force_b : array_like, shape (K, 3), optional
        f_k for ``"g_sensitivity"``. [m/s²]
    rate_b : array_like, shape (K, 3), optional
        ω_k for ``"lever_arm"``. [rad/s]
    angular_accel_b : array_like, shape (K, 3), optional
        ω̇_k for ``"lever_arm"`` (zero when omitted: constant rates). [rad/s²]

    Returns
    -------
    LinearDesign
        H of shape (3K, p) and the column names.

    Raises
    ------
    InvalidInputError
        An unknown or repeated term, a term without the inputs it needs, or arrays that are
        not finite (K, 3).

    Examples
    --------
    >>> d = build_design([[0.0, 0.0, 9.8]], ["bias", "k2"])
    >>> d.H.shape, d.param_names
    ((3, 6), ('bias_x', 'bias_y', 'bias_z', 'K2_x', 'K2_y', 'K2_z'))
    """
    x = as_array(input_b, "input_b", shape=(None, 3))
    k = x.shape[0]
    unknown = [t for t in terms if t not in TRIAD_TERMS]
    if unknown or len(set(terms)) != len(terms):
        raise InvalidInputError(f"`terms` must be distinct names of {list(TRIAD_TERMS)}; got "
                                f"{list(terms)}")
    blocks: list[_F64] = []
    names: list[str] = []
    for term in terms:
        if term == "bias":
            block = np.zeros((3 * k, 3))
            for i in range(3):
                block[i::3, i] = 1.0
            blocks.append(block)
            names += [f"bias_{a}" for a in AXES]
        elif term == "scale_misalignment":
            blocks.append(_per_sensor_rows(k, np.repeat(x[:, None, :], 3, axis=1)))
            names += [f"M_{i}{j}" for i in AXES for j in AXES]
        elif term == "k2":
            block = np.zeros((3 * k, 3))
            for i in range(3):
                block[i::3, i] = x[:, i] ** 2
            blocks.append(block)
            names += [f"K2_{a}" for a in AXES]
        elif term == "g_sensitivity":
            if specific_force_b is None:
                raise InvalidInputError("the 'g_sensitivity' term needs `specific_force_b`")
            f = as_array(specific_force_b, "specific_force_b", shape=(k, 3))
            blocks.append(_per_sensor_rows(k, np.repeat(f[:, None, :], 3, axis=1)))
            names += [f"G_{i}{j}" for i in AXES for j in AXES]
        else:  # lever_arm
            if rate_b is None:
                raise InvalidInputError("the 'lever_arm' term needs `rate_b`")
            w = as_array(rate_b, "rate_b", shape=(k, 3))
            dw = (np.zeros((k, 3)) if angular_accel_b is None
                  else as_array(angular_accel_b, "angular_accel_b", shape=(k, 3)))
            c = np.array([_skew(dw[n]) + _skew(w[n]) @ _skew(w[n]) for n in range(k)])
            blocks.append(_per_sensor_rows(k, c.reshape(k, 3, 3)))
            names += [f"L_{i}{j}" for i in AXES for j in AXES]
    H = np.hstack(blocks) if blocks else np.zeros((3 * k, 0))
    H.setflags(write=False)
    return LinearDesign(H=H, param_names=tuple(names))
