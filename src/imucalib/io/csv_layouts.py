"""Known CSV layouts of IMU logs and the column map that reads them (pure functions).

Contents
--------
:func:`detect_layout`, :func:`build_csv_mapping` → :class:`CsvMapping`, :data:`ROS_IMU_FIELDS`,
:func:`parse_pairs`

Layouts
-------
``"canonical"``
    imucalib's own names (``time_s``, ``gyro_x_rps`` …, or ``name [unit]``), or any file read
    through a user's ``column_map``.
``"ros-imu"``
    ``rostopic echo -b x.bag -p /imu > imu.csv`` of a ``sensor_msgs/Imu`` topic: header
    ``%time,field.header.seq,field.header.stamp,field.header.frame_id,field.orientation.x,…,
    field.angular_velocity.x,…,field.linear_acceleration.x,…``. ``field.header.stamp`` (the
    sensor time, ns) becomes ``time_s``, ``field.angular_velocity.{x,y,z}`` (rad/s) the gyro
    and ``field.linear_acceleration.{x,y,z}`` (m/s²) the accelerometer; the other fields are
    skipped. Detected when the header holds ``field.header.stamp`` and the angular-velocity or
    linear-acceleration fields.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TIME_COLUMN
from imucalib.errors import InvalidInputError

__all__ = ["LAYOUTS", "ROS_IMU_FIELDS", "CsvMapping", "build_csv_mapping", "detect_layout",
           "parse_pairs"]

LAYOUTS = ("canonical", "ros-imu")
_ROS_TIME = "field.header.stamp"
#: ``rostopic echo -p`` field → (canonical column, unit).
ROS_IMU_FIELDS: dict[str, tuple[str, str]] = {
    _ROS_TIME: (TIME_COLUMN, "ns"),
    **{f"field.angular_velocity.{a}": (c, "rad/s") for a, c in zip("xyz", GYRO_COLUMNS,
                                                                    strict=True)},
    **{f"field.linear_acceleration.{a}": (c, "m/s^2") for a, c in zip("xyz", ACCEL_COLUMNS,
                                                                       strict=True)},
}


@dataclass(frozen=True)
class CsvMapping:
    """How to read one CSV (the keywords of :func:`~imucalib.io.csv_import.read_imu_csv`)."""

    layout: str
    column_map: dict[str, str]  # header field → canonical name
    units: dict[str, str]  # canonical name → unit, where the header gives none
    only: tuple[str, ...] | None  # header fields to read (None: all)


def detect_layout(headers: Sequence[str]) -> str:
    """Return the layout of a header (module docstring): ``"ros-imu"`` or ``"canonical"``."""
    fields = {h.strip() for h in headers}
    imu = any(f in fields for f in ROS_IMU_FIELDS if f != _ROS_TIME)
    return "ros-imu" if _ROS_TIME in fields and imu else "canonical"


def parse_pairs(text: str | None, option: str) -> dict[str, str]:
    """Parse ``a=b,c=d`` into a dict; InvalidInputError names `option` and the bad item."""
    out: dict[str, str] = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise InvalidInputError(f"{option}: expected NAME=VALUE items separated by commas; "
                                    f"got {item.strip()!r}")
        out[key.strip()] = value.strip()
    return out


def build_csv_mapping(headers: Sequence[str], *, column_map: Mapping[str, str] | None = None,
                      units: Mapping[str, str] | None = None, gyro_unit: str | None = None,
                      accel_unit: str | None = None, time_column: str | None = None,
                      time_unit: str | None = None) -> CsvMapping:
    """Build the column map and units that read a CSV of header `headers`.

    The layout is detected (:func:`detect_layout`); the user's `column_map` and `units` are
    applied over it. `gyro_unit` / `accel_unit` give the unit of every gyro / accelerometer
    column whose unit is not given otherwise; `time_column` names the time field (mapped to
    ``time_s``) and `time_unit` its unit.

    Raises
    ------
    InvalidInputError
        `time_column` not in the header.
    """
    fields = [h.strip() for h in headers]
    layout = detect_layout(fields)
    cmap: dict[str, str] = {}
    unit_of: dict[str, str] = {}
    only: tuple[str, ...] | None = None
    if layout == "ros-imu":
        present = [f for f in ROS_IMU_FIELDS if f in fields]
        cmap = {f: ROS_IMU_FIELDS[f][0] for f in present}
        unit_of = {ROS_IMU_FIELDS[f][0]: ROS_IMU_FIELDS[f][1] for f in present}
        only = tuple(present)
    cmap.update(column_map or {})
    if time_column is not None:
        if time_column not in fields:
            raise InvalidInputError(f"--time-column {time_column!r} is not in the header; "
                                    f"found {fields}")
        cmap = {k: v for k, v in cmap.items() if v != TIME_COLUMN}
        cmap[time_column] = TIME_COLUMN
    if only is not None:
        only = tuple(dict.fromkeys([*only, *cmap]))
    for canonical in cmap.values():
        if gyro_unit and canonical in GYRO_COLUMNS:
            unit_of[canonical] = gyro_unit
        elif accel_unit and canonical in ACCEL_COLUMNS:
            unit_of[canonical] = accel_unit
    for name in fields:  # canonical names in the file itself
        if gyro_unit and name in GYRO_COLUMNS:
            unit_of[name] = gyro_unit
        elif accel_unit and name in ACCEL_COLUMNS:
            unit_of[name] = accel_unit
    if time_unit:
        unit_of[TIME_COLUMN] = time_unit
    unit_of.update(units or {})
    return CsvMapping(layout, cmap, unit_of, only)
