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
    skipped. Detected when the header holds ``field.header.stamp`` (or, lacking it, ``%time``,
    the bag's receive time in ns) and the angular-velocity or linear-acceleration fields.
``"imucal"``
    The names of imucal (``acc_x``, ``acc_y``, ``acc_z`` in m/s², ``gyr_x``, ``gyr_y``,
    ``gyr_z`` in °/s), with a time column ``t``, ``time`` or ``timestamp`` (s) or none (give the
    sample rate).
``"plain"``
    ``ax, ay, az, gx, gy, gz`` (any case), time column as for imucal; the units are not implied
    by these names and must be given (``gyro_unit``, ``accel_unit``).
``"imu_tk"``
    imu_tk's text files (Tedaldi et al. 2014): no header, blank-separated ``time x y z`` rows,
    one file for the gyro and one for the accelerometer (read by
    :func:`imucalib.io.import_spec.read_imu_table` with ``accel_file``).

Column-map items are ``vendor=canonical`` (``GyrX=gyro_x_rps``) or ``short=vendor``
(``gx=GyroX``), where the short names are :data:`SHORT_NAMES` (``t``/``time`` for the time).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS, TEMPERATURE_COLUMN, TIME_COLUMN
from imucalib.errors import InvalidInputError

__all__ = ["IMUCAL_FIELDS", "LAYOUTS", "ROS_IMU_FIELDS", "SHORT_NAMES", "CsvMapping",
           "build_csv_mapping", "detect_layout", "normalize_column_map", "parse_pairs"]

LAYOUTS = ("canonical", "ros-imu", "imucal", "plain", "imu_tk")
_ROS_TIME = "field.header.stamp"
_ROS_BAG_TIME = "%time"
#: Short names a column map may use for the canonical columns.
SHORT_NAMES: dict[str, str] = {
    "t": TIME_COLUMN, "time": TIME_COLUMN,
    **{f"g{a}": c for a, c in zip("xyz", GYRO_COLUMNS, strict=True)},
    **{f"a{a}": c for a, c in zip("xyz", ACCEL_COLUMNS, strict=True)},
    "temp": TEMPERATURE_COLUMN, "temperature": TEMPERATURE_COLUMN,
}
_CANONICAL = frozenset((TIME_COLUMN, *GYRO_COLUMNS, *ACCEL_COLUMNS, TEMPERATURE_COLUMN))
_TIME_NAMES = ("t", "time", "timestamp", "time_s")
#: imucal's column → (canonical column, unit).
IMUCAL_FIELDS: dict[str, tuple[str, str]] = {
    **{f"gyr_{a}": (c, "deg/s") for a, c in zip("xyz", GYRO_COLUMNS, strict=True)},
    **{f"acc_{a}": (c, "m/s^2") for a, c in zip("xyz", ACCEL_COLUMNS, strict=True)},
}
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
    """Return the layout of a header (module docstring).

    One of ``"ros-imu"``, ``"imucal"``, ``"plain"`` or ``"canonical"`` (anything else).
    """
    fields = {h.strip() for h in headers}
    imu = any(f in fields for f in ROS_IMU_FIELDS if f != _ROS_TIME)
    if imu and (_ROS_TIME in fields or _ROS_BAG_TIME in fields):
        return "ros-imu"
    if sum(f in fields for f in IMUCAL_FIELDS) >= 3:
        return "imucal"
    lower = {f.lower() for f in fields}
    if sum(k in lower for k in SHORT_NAMES if len(k) == 2) >= 3:
        return "plain"
    return "canonical"


def normalize_column_map(pairs: Mapping[str, str], option: str = "--column-map"
                         ) -> dict[str, str]:
    """Turn column-map items into vendor column → canonical name.

    An item is ``vendor=canonical`` or ``canonical=vendor``, the canonical side a canonical
    column name or one of :data:`SHORT_NAMES` (``gx=GyroX``, ``GyroX=gyro_x_rps``).

    Raises
    ------
    InvalidInputError
        An item with neither side canonical (the message lists the names expected).
    """
    out: dict[str, str] = {}
    for key, value in pairs.items():
        if value in _CANONICAL or value in SHORT_NAMES:
            out[key] = SHORT_NAMES.get(value, value)
        elif key in _CANONICAL or key in SHORT_NAMES:
            out[value] = SHORT_NAMES.get(key, key)
        else:
            raise InvalidInputError(
                f"{option}: in {key}={value} neither side is a quantity; expected "
                f"{', '.join(SHORT_NAMES)} or a canonical name ({', '.join(sorted(_CANONICAL))}) "
                "on one side and the file's column on the other")
    return out


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
        table = dict(ROS_IMU_FIELDS)
        if _ROS_TIME not in fields:
            table[_ROS_BAG_TIME] = (TIME_COLUMN, "ns")
        present = [f for f in table if f in fields]
        cmap = {f: table[f][0] for f in present}
        unit_of = {table[f][0]: table[f][1] for f in present}
        only = tuple(present)
    elif layout in ("imucal", "plain"):
        for f in fields:
            if layout == "imucal" and f in IMUCAL_FIELDS:
                cmap[f], unit_of[IMUCAL_FIELDS[f][0]] = IMUCAL_FIELDS[f]
            elif layout == "plain" and f.lower() in SHORT_NAMES and len(f) == 2:
                cmap[f] = SHORT_NAMES[f.lower()]
        time_field = next((f for f in fields if f.lower() in _TIME_NAMES), None)
        if time_field is not None:
            cmap[time_field] = TIME_COLUMN
            unit_of.setdefault(TIME_COLUMN, "s")
        only = tuple(cmap)
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
    if layout == "plain":
        for kind, cols, option in (("gyro", GYRO_COLUMNS, "--gyro-unit deg/s|rad/s|counts"),
                                   ("accelerometer", ACCEL_COLUMNS,
                                    "--accel-unit g|m/s^2|counts")):
            bare = [f for f, c in cmap.items() if c in cols and c not in unit_of]
            if bare:
                raise InvalidInputError(
                    f"the {kind} columns {bare} (layout `ax,ay,az,gx,gy,gz`) carry no unit; "
                    f"give it with `{option}` (or `units` in the --import file)")
    return CsvMapping(layout, cmap, unit_of, only)
