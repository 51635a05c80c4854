"""Apply a calibration to data: measured → corrected (estimated true) gyro and accelerometer.

Contents
--------
:func:`correct_imu`
    Array form: ``(gyro_rps, accel_mps2)`` in, corrected pair out.
:func:`correct_imu_frame`
    DataFrame form over the canonical columns (``gyro_x_rps`` … ``accel_z_mps2``).

Both refuse data whose units differ from the result's ``input_units`` (a result made from SI data
applied to raw counts is an error, not a silent mistake). The accelerometer is corrected first
(exact inverse of y = b + (I + M)·x); a gyro g-sensitivity is then removed with the corrected
specific force (:func:`~imucalib.models.triad.correct_triad`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_samples3
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.errors import InvalidInputError, UnitError
from imucalib.models.result import CalibrationResult
from imucalib.models.triad import correct_triad

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["correct_imu", "correct_imu_frame"]

_F64 = NDArray[np.float64]


def _check_units(result: CalibrationResult, gyro_unit: str, accel_unit: str) -> None:
    for triad, unit in (("gyro", gyro_unit), ("accel", accel_unit)):
        expected = result.input_units.get(triad)
        if result.has_triad(triad) and expected is not None and unit != expected:
            raise UnitError(f"the result for {result.sensor_id} was made from {triad} data in "
                            f"{expected!r}; the data given are in {unit!r}")


def correct_imu(gyro_rps: ArrayLike | None, accel_mps2: ArrayLike | None,
                result: CalibrationResult, *, gyro_unit: str = "rad/s",
                accel_unit: str = "m/s^2") -> tuple[_F64 | None, _F64 | None]:
    """Correct measured outputs with a calibration result.

    Parameters
    ----------
    gyro_rps : array_like, shape (n, 3), or None
        Measured gyro output, sensor frame. [rad/s]
    accel_mps2 : array_like, shape (n, 3), or None
        Measured accelerometer output, sensor frame. [m/s²]
    result : CalibrationResult
        The calibration; a triad it does not calibrate is passed through unchanged.
    gyro_unit, accel_unit : str
        The units the data are in; they must equal ``result.input_units``.

    Returns
    -------
    gyro_rps, accel_mps2 : ndarray, shape (n, 3), or None
        Corrected (estimated true) angular rate [rad/s] and specific force [m/s²], body frame.

    Raises
    ------
    UnitError
        If the data units differ from the result's.
    InvalidInputError
        For arrays of the wrong shape, non-finite values, or a gyro g-sensitivity without
        accelerometer data.
    """
    _check_units(result, gyro_unit, accel_unit)
    accel = None if accel_mps2 is None else as_samples3(accel_mps2, "accel_mps2")
    gyro = None if gyro_rps is None else as_samples3(gyro_rps, "gyro_rps")
    if accel is not None and gyro is not None and accel.shape != gyro.shape:
        raise InvalidInputError(f"`gyro_rps` and `accel_mps2` must have the same shape; got "
                                f"{gyro.shape} and {accel.shape}")
    if accel is not None and result.has_triad("accel"):
        zeros = np.zeros_like(accel)
        accel = correct_triad(result.triad_model("accel"), accel, rate_b_rps=zeros,
                              angular_accel_b_rps2=zeros)
    if gyro is not None and result.has_triad("gyro"):
        model = result.triad_model("gyro")
        if np.any(model.g_sensitivity != 0.0) and accel is None:
            raise InvalidInputError("this result has a gyro g-sensitivity: correcting the gyro "
                                    "needs the accelerometer data too")
        gyro = correct_triad(model, gyro, specific_force_b_mps2=accel)
    return gyro, accel


def correct_imu_frame(df: pd.DataFrame, result: CalibrationResult) -> pd.DataFrame:
    """Correct the canonical columns of a DataFrame (others are kept as they are).

    Raises
    ------
    InvalidInputError
        If a triad's columns are only partly present.
    UnitError
        If ``df.attrs["units"]`` names units that differ from the result's.
    """
    units = df.attrs.get("units", {})
    out = df.copy()
    cols = {}
    for triad, names in (("gyro", GYRO_COLUMNS), ("accel", ACCEL_COLUMNS)):
        present = [c for c in names if c in df.columns]
        if present and len(present) != 3:
            raise InvalidInputError(f"{triad} columns must all be present ({list(names)}); got "
                                    f"{present}")
        cols[triad] = df[list(names)].to_numpy(dtype=np.float64) if present else None
    gyro_unit = units.get(GYRO_COLUMNS[0], "rad/s")
    accel_unit = units.get(ACCEL_COLUMNS[0], "m/s^2")
    gyro, accel = correct_imu(cols["gyro"], cols["accel"], result, gyro_unit=gyro_unit,
                              accel_unit=accel_unit)
    if gyro is not None:
        out[list(GYRO_COLUMNS)] = gyro
    if accel is not None:
        out[list(ACCEL_COLUMNS)] = accel
    return out
