"""Frames, axis order, sign conventions and canonical column names, defined once.

Frames
------
``s``
    Sensor frame: the (non-orthogonal) sensitive axes of a triad.
``b``
    Body frame of the IMU: orthogonal, right-handed, fixed to the case; its origin is the IMU's
    reference point (the accelerometer triad's centre of percussion by convention).
``m``
    Mount (fixture) frame: fixed to the fixture carried by the table's platform; its origin is the
    point where the table's axes intersect (the rotation centre). An IMU on the fixture has a fixed
    rotation ``rot_mb`` and lever arm ``lever_arm_m_m`` (position of the IMU origin in ``m``).
``p``
    Platform frame of a rate table: fixed to the innermost moving axis. With an ideally mounted
    fixture ``m`` coincides with ``p``.
``t``
    Table base frame: fixed to the ground. ``z_t`` points **up** (against gravity); ``x_t``
    points at
    the station's heading (azimuth from North, clockwise seen from above); ``y_t = z_t × x_t``.
``n``
    Local-level navigation frame, **NED**: x North, y East, z Down.
``e``
    Earth-centred Earth-fixed (WGS-84).

Rotations are :class:`scipy.spatial.transform.Rotation` objects named ``rot_ab``; ``rot_ab`` maps
vectors expressed in frame ``b`` into frame ``a``: ``v_a = rot_ab.apply(v_b)``. Matrices are
``mat_ab`` with the same meaning.

Sign conventions
----------------
- Accelerometers measure **specific force** f = a − G (kinematic acceleration minus gravitation).
  A stationary, level IMU whose z axis points up reads f_z = +g.
- Gyros measure the **inertial** angular rate of the body, ω_ib, which includes Earth rate.
- Positive rotation is right-handed about the axis vector.
- Temperature is in °C (suffix ``_degc``); temperature rate in °C/s (``_degc_ps``).

Noise densities
---------------
Densities are the **two-sided** coefficient N of IEEE 952 (so σ_Allan(1 s) = N and a discrete
sample of a white process at interval Δt has standard deviation N/√Δt); datasheet one-sided values
are N·√2. See :mod:`imucalib.models.noise`.

Canonical names
---------------
:data:`AXES` (``"x", "y", "z"``), :data:`GYRO_COLUMNS`, :data:`ACCEL_COLUMNS`,
:data:`IMU_COLUMNS`, :data:`TIME_COLUMN`, :data:`COUNTER_COLUMN`, :data:`TEMPERATURE_COLUMN`.
"""

from __future__ import annotations

__all__ = [
    "ACCEL_COLUMNS",
    "AXES",
    "COUNTER_COLUMN",
    "FRAMES",
    "GYRO_COLUMNS",
    "IMU_COLUMNS",
    "TABLE_AXIS_VECTORS",
    "TEMPERATURE_COLUMN",
    "TIME_COLUMN",
]

#: Frame letters and their one-line meaning.
FRAMES: dict[str, str] = {
    "s": "sensor (non-orthogonal sensitive axes of a triad)",
    "b": "IMU body (orthogonal, case-fixed; origin at the IMU reference point)",
    "m": "mount/fixture (on the table platform; origin at the rotation centre)",
    "p": "table platform (innermost moving axis)",
    "t": "table base (ground-fixed, z up, x at the station heading)",
    "n": "local level, North-East-Down",
    "e": "Earth-centred Earth-fixed (WGS-84)",
}

AXES: tuple[str, str, str] = ("x", "y", "z")

TIME_COLUMN = "time_s"
COUNTER_COLUMN = "counter"
TEMPERATURE_COLUMN = "temperature_degc"
GYRO_COLUMNS: tuple[str, str, str] = ("gyro_x_rps", "gyro_y_rps", "gyro_z_rps")
ACCEL_COLUMNS: tuple[str, str, str] = ("accel_x_mps2", "accel_y_mps2", "accel_z_mps2")
IMU_COLUMNS: tuple[str, ...] = (*GYRO_COLUMNS, *ACCEL_COLUMNS)

#: Nominal direction of each named rate-table axis in its parent frame (the base t for the outer
#: axis): the dual-axis table of P1 turns pitch about −y_t (outer) and roll about x (inner), so
#: that (pitch 90°, roll 0°) puts x up and (0°, 90°) puts y up; a single-axis table and a
#: centrifuge turn about z_t (up).
TABLE_AXIS_VECTORS: dict[str, tuple[float, float, float]] = {
    "pitch": (0.0, -1.0, 0.0),
    "roll": (1.0, 0.0, 0.0),
    "azimuth": (0.0, 0.0, 1.0),
    "spin": (0.0, 0.0, 1.0),
}
