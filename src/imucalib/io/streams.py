"""Canonical stream layouts of a Recording: the columns each kind of device writes.

Every station (the digital twin, real drivers) writes its devices' data with these layouts, so
that every analysis finds the same column names and units.

Contents
--------
:func:`imu_stream_spec`
    ``/streams/imu/<name>``: time, device time, sample counter, gyro, accelerometer, internal
    temperature and a saturation flag.
:func:`imu_truth_stream_spec`
    ``/truth/streams/imu/<name>``: the twin's true inputs (never read by analysis).
:func:`motion_stream_spec`
    ``/streams/table/<name>`` or ``/streams/centrifuge/<name>``: measured angle and rate per axis.
:func:`chamber_stream_spec`
    ``/streams/chamber/<name>``: air temperature and setpoint.
:func:`axis_columns`
    Column names of one axis of a motion stream.

Column names follow :mod:`imucalib.conventions`: ``gyro_x_rps`` … ``accel_z_mps2``,
``temperature_degc``, ``counter``; a motion stream has ``angle_<axis>_rad`` and
``rate_<axis>_rps`` for each axis name (``pitch``, ``roll``, ``azimuth``, ``arm`` …).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from imucalib.conventions import (
    ACCEL_COLUMNS,
    COUNTER_COLUMN,
    GYRO_COLUMNS,
    TEMPERATURE_COLUMN,
)
from imucalib.io._schema import ColumnSpec, StreamSpec

__all__ = [
    "DEVICE_CENTRIFUGE",
    "DEVICE_CHAMBER",
    "DEVICE_IMU",
    "DEVICE_TABLE",
    "IMU_TRUTH_COLUMNS",
    "axis_columns",
    "chamber_stream_spec",
    "imu_stream_spec",
    "imu_truth_stream_spec",
    "motion_stream_spec",
]

DEVICE_IMU = "imu"
DEVICE_TABLE = "table"
DEVICE_CENTRIFUGE = "centrifuge"
DEVICE_CHAMBER = "chamber"

#: Columns of an IMU truth stream (besides ``time_s``, the station receive time).
IMU_TRUTH_COLUMNS: tuple[str, ...] = (
    "true_time_s",
    "true_rate_x_rps", "true_rate_y_rps", "true_rate_z_rps",
    "true_force_x_mps2", "true_force_y_mps2", "true_force_z_mps2",
    "true_temperature_degc",
)


def imu_stream_spec(name: str, *, quantity: str = "si", gyro_lsb_rps: float | None = None,
                    accel_lsb_mps2: float | None = None,
                    temperature_lsb_degc: float | None = None) -> StreamSpec:
    """Return the layout of an IMU stream.

    Parameters
    ----------
    name : str
        The unit's name (serial number); the stream is ``/streams/imu/<name>``.
    quantity : {"si", "raw"}
        Whether gyro and accelerometer columns hold SI values (rad/s, m/s²) or raw output.
    gyro_lsb_rps, accel_lsb_mps2, temperature_lsb_degc : float, optional
        The output's LSB, when the device delivers integer counts of it: the column is then
        stored as int32 counts with that ``scale`` and read back as the same float64 values
        (``docs/recording-format.md``, *Size and compression*); values off that grid are
        refused when appended. Omitted: float64. [rad/s], [m/s²], [°C]
    """
    gyro_unit, accel_unit = ("rad/s", "m/s^2") if quantity == "si" else ("counts", "counts")

    def counts(lsb: float | None) -> dict[str, Any]:
        return {} if lsb is None else {"dtype": "i4", "scale": lsb}

    cols: dict[str, ColumnSpec] = {
        "device_time_s": ColumnSpec("s", description="the IMU's own timestamp"),
        COUNTER_COLUMN: ColumnSpec("counts", dtype="i8", quantity="raw",
                                   description="sample counter (wraps; gaps show lost samples)"),
    }
    for col, axis in zip(GYRO_COLUMNS, "xyz", strict=True):
        cols[col] = ColumnSpec(gyro_unit, quantity=quantity,
                               description=f"gyro {axis}, sensor frame", **counts(gyro_lsb_rps))
    for col, axis in zip(ACCEL_COLUMNS, "xyz", strict=True):
        cols[col] = ColumnSpec(accel_unit, quantity=quantity,
                               description=f"accelerometer {axis}, sensor frame",
                               **counts(accel_lsb_mps2))
    cols[TEMPERATURE_COLUMN] = ColumnSpec("degC", description="internal temperature sensor",
                                          **counts(temperature_lsb_degc))
    cols["saturated"] = ColumnSpec("bool", dtype="b1", quantity="raw",
                                   description="any channel at its range")
    return StreamSpec(DEVICE_IMU, name, cols)


def imu_truth_stream_spec(name: str) -> StreamSpec:
    """Return the layout of a twin IMU's truth stream (true inputs at each delivered sample)."""
    units = {"true_time_s": "s", "true_temperature_degc": "degC"}
    cols = {c: ColumnSpec(units.get(c, "rad/s" if "rate" in c else "m/s^2"))
            for c in IMU_TRUTH_COLUMNS}
    return StreamSpec(DEVICE_IMU, name, cols)


def axis_columns(axis_name: str) -> tuple[str, str]:
    """Return the (angle, rate) column names of one axis: ``angle_<a>_rad``, ``rate_<a>_rps``."""
    return f"angle_{axis_name}_rad", f"rate_{axis_name}_rps"


def motion_stream_spec(device: str, name: str, axis_names: Sequence[str]) -> StreamSpec:
    """Return the layout of a rate-table or centrifuge feedback stream.

    Parameters
    ----------
    device : {"table", "centrifuge"}
        Device kind.
    name : str
        The unit's name (e.g. ``"main"``).
    axis_names : sequence of str
        Axis names, outer first; each gives a measured angle [rad, unwrapped] and rate [rad/s].
    """
    cols: dict[str, ColumnSpec] = {}
    for axis in axis_names:
        angle, rate = axis_columns(axis)
        cols[angle] = ColumnSpec("rad", description=f"measured {axis} angle (unwrapped)")
        cols[rate] = ColumnSpec("rad/s", description=f"measured {axis} rate")
    return StreamSpec(device, name, cols)


def chamber_stream_spec(name: str) -> StreamSpec:
    """Return the layout of a thermal-chamber stream (air temperature and setpoint)."""
    return StreamSpec(DEVICE_CHAMBER, name, {
        "temperature_degc": ColumnSpec("degC", description="chamber air temperature"),
        "setpoint_degc": ColumnSpec("degC", description="controller setpoint"),
    })
