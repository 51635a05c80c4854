"""P1's step roles: what each recorded step is for (``p1.<purpose>``, docs/p1.md).

The plan generator (:mod:`.plan`) sets them, the runner stores them with each executed step and
the analysis (:mod:`.observations`) selects its windows by them (docs/recording-format.md, "Step
roles"). A step that only prepares (warm-up, an operator check, moving to a position) has none.

:data:`P1_ACCEL_POSITION` ``"p1.accel-position"``
    One of the six static positions; calibrates the accelerometer triad (and gives the gyro
    static rows).
:data:`P1_GYRO_BIAS` ``"p1.gyro-bias"``
    The long level static record; the gyro bias and the noise model of the window means.
:data:`P1_GYRO_RATE` ``"p1.gyro-rate"``
    A calibration rate point (``commanded`` gives ``axis``, ``rate_dps`` and ``revolutions``);
    a zero rate is observed as a static window.
:data:`P1_HELD_OUT_POSITION` ``"p1.held-out-position"``
    A position kept out of the fit, for the accelerometer accuracy verification.
:data:`P1_HELD_OUT_RATE` ``"p1.held-out-rate"``
    A rate kept out of the fit, for the gyro accuracy verification.

Version 1 Recordings, which had no roles, get these from their tags
(:func:`imucalib.io.step_roles.role_from_tags`, a frozen fact of the file format).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["P1_ACCEL_POSITION", "P1_GYRO_BIAS", "P1_GYRO_RATE", "P1_HELD_OUT_POSITION",
           "P1_HELD_OUT_RATE", "ROLES"]

P1_ACCEL_POSITION: Final = "p1.accel-position"
P1_GYRO_BIAS: Final = "p1.gyro-bias"
P1_GYRO_RATE: Final = "p1.gyro-rate"
P1_HELD_OUT_POSITION: Final = "p1.held-out-position"
P1_HELD_OUT_RATE: Final = "p1.held-out-rate"

#: Every P1 role and what the step is for (the module docstring says more).
ROLES: Final[Mapping[str, str]] = {
    P1_ACCEL_POSITION: "one of the six static positions (accelerometer triad, gyro statics)",
    P1_GYRO_BIAS: "the long level static record (gyro bias, noise model of the window means)",
    P1_GYRO_RATE: "a calibration rate point over whole revolutions (axis, rate)",
    P1_HELD_OUT_POSITION: "a position kept out of the fit (accelerometer verification)",
    P1_HELD_OUT_RATE: "a rate kept out of the fit (gyro verification)",
}
