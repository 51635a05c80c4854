"""The closed form of the g-sensitivity drift model on the six axis-up positions.

The drift model (docs/g-sensitivity.md, equations (1)–(4)) and its generalised least-squares fit
are :mod:`~imucalib.procedures.common.drift_model` (shared with the random-drift test;
:class:`DriftFit` and :func:`fit_drift_model` are re-exported here). The closed form of the six
axis-up positions (:func:`six_position_closed_form`) is (1) solved exactly, M taken as zero:
D0_i = (1/6)·Σ d_ik and D_ji = (d_i(+j) − d_i(−j))/(2g).

Contents
--------
:class:`DriftFit`, :func:`fit_drift_model`, :func:`six_position_closed_form`
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InvalidInputError
from imucalib.procedures.common.drift_model import DriftFit, fit_drift_model

__all__ = ["DriftFit", "fit_drift_model", "six_position_closed_form"]

_F64 = NDArray[np.float64]


def six_position_closed_form(gyro_mean_rps: _F64, omega_ref_rps: _F64, gravity_mps2: float
                             ) -> _F64:
    """Return (3, 4) coefficients from the six axis-up positions.

    In the order +z, −z, +x, −x, +y, −y (module docstring; M taken as zero).
    """
    d = np.asarray(gyro_mean_rps, float) - np.asarray(omega_ref_rps, float)
    if d.shape != (6, 3):
        raise InvalidInputError(f"the closed form takes the 6 axis-up positions; got shape "
                                f"{d.shape}")
    out = np.zeros((3, 4))
    out[:, 0] = d.mean(axis=0)
    for j, (up, down) in enumerate(((2, 3), (4, 5), (0, 1))):
        out[:, 1 + j] = (d[up] - d[down]) / (2.0 * gravity_mps2)
    return out
