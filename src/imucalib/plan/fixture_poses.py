"""The six poses of a cube fixture on a vertical-axis table (the remounts of P2).

A remount places the fixture on the table platform with one of its axes pointing up, along the
table's spin axis z_p, then optionally turns it about the vertical by a yaw angle. This module
names the poses and gives the rotation ``R_pm`` of each: it maps fixture-frame (m) vectors into
the platform frame p (z_p the spin axis, up). It belongs to the plan layer so that the plan schema
(``OperatorCheckStep.remount``), the twin (:mod:`imucalib.sim`) and analysis code share one table.

Contents
--------
:data:`FixtureAxis`
    The names of the six poses: the fixture axis that points up.
:data:`FIXTURE_POSES`
    The base rotation ``R_pm`` of each pose (yaw 0), as a 3×3 tuple of rows.
:func:`rot_pm_for_pose`
    ``R_pm`` of a pose and a yaw, as a 3×3 numpy matrix.

Poses
-----
Each base rotation is the single right-angle (or half-turn) rotation about x_m or y_m that brings
the named axis to +z_p; x_m stays horizontal where it can (every pose but ±x), y_m stays put in
the ±x poses. Columns are the images of x_m, y_m, z_m in p:

=====  ==============  ==============================
pose   R_pm (yaw 0)    R_pm·x_m, R_pm·y_m, R_pm·z_m
=====  ==============  ==============================
+z     identity        +x_p, +y_p, +z_p
−z     R_x(180°)       +x_p, −y_p, −z_p
+y     R_x(+90°)       +x_p, +z_p, −y_p
−y     R_x(−90°)       +x_p, −z_p, +y_p
+x     R_y(−90°)       +z_p, +y_p, −x_p
−x     R_y(+90°)       −z_p, +y_p, +x_p
=====  ==============  ==============================

With a yaw ψ (degrees, positive counter-clockwise seen from above) the rotation is
``R_z(ψ) · R_pm(pose)``: the fixture is placed, then turned about the vertical. For the cube of
:func:`imucalib.sim.fixture.hexahedral_fixture`, the IMU at the centre of the face whose normal is
the named axis then has its body frame aligned with p (``R_pm · rot_mb`` = identity at yaw 0).
"""

from __future__ import annotations

import math
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

__all__ = ["FIXTURE_AXES", "FIXTURE_POSES", "FixtureAxis", "rot_pm_for_pose"]

#: A fixture axis pointing up: the pose of a remount.
FixtureAxis = Literal["+z", "-z", "+y", "-y", "+x", "-x"]

#: The pose names in the order of the cube's faces (+z, −z, +y, −y, +x, −x).
FIXTURE_AXES: tuple[str, ...] = get_args(FixtureAxis)

#: Base rotation R_pm (yaw 0) of each pose, rows of a 3×3 matrix (see the module docstring).
FIXTURE_POSES: dict[str, tuple[tuple[float, float, float], ...]] = {
    "+z": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    "-z": ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
    "+y": ((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "-y": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    "+x": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
    "-x": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)),
}


def rot_pm_for_pose(up: str, yaw_deg: float = 0.0) -> NDArray[np.float64]:
    """Return R_pm of the fixture placed with axis `up` pointing up, then yawed by `yaw_deg`.

    Parameters
    ----------
    up : {"+z", "-z", "+y", "-y", "+x", "-x"}
        The fixture axis along the table's spin axis (up).
    yaw_deg : float
        Rotation of the placed fixture about the vertical z_p, counter-clockwise from above. [°]

    Returns
    -------
    ndarray, shape (3, 3)
        Proper rotation mapping fixture-frame vectors into the platform frame.

    Raises
    ------
    ValueError
        If `up` is not one of the six pose names or `yaw_deg` is not finite.
    """
    if up not in FIXTURE_POSES:
        raise ValueError(f"`up` must be one of {list(FIXTURE_AXES)}; got {up!r}")
    yaw = float(yaw_deg)
    if not math.isfinite(yaw):
        raise ValueError(f"`yaw_deg` must be finite; got {yaw_deg!r}")
    base = np.array(FIXTURE_POSES[up], dtype=np.float64)
    if yaw == 0.0:
        return base
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return rz @ base
