"""Step roles: what a recorded step is for in its procedure (the ``role`` field of ``/steps``).

A role is ``"<procedure>.<purpose>"``. Plan generators set them, the runner stores them with each
executed step, and an analysis selects its windows by them, so that a Recording explains itself
without the plan that made it (``docs/recording-format.md``, "Step roles").

P1 (two-dimensional calibration on a dual-axis table):

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

Allan: :data:`ALLAN_STATIC` ``"allan.static"``, a static record whose noise is characterised.

P2 (array full-temperature calibration, docs/p2.md); every P2 step carries the tags
``point=<k>`` (its temperature point) and ``leg=heating|cooling``, the held-out points also
``held-out``, and the steps after a remount ``pose=<axis>`` (the fixture axis up):

:data:`P2_SOAK` ``"p2.soak"``
    Reach a temperature point and wait until chamber and IMUs are stable.
:data:`P2_REMOUNT` ``"p2.remount"``
    The operator places the fixture with another face up (an operator check).
:data:`P2_STATIC` ``"p2.static"``
    A static record in the current pose (tag ``angle=<deg>``: at two angles 180° apart).
:data:`P2_RATE` ``"p2.rate"``
    A turn at +ω or −ω over whole revolutions.

P3 (accelerometer K2 on a centrifuge with dynamic-unbalance compensation, docs/p3.md); every
P3 step of a configuration carries the tag ``config=<k>`` (1: reference A on the test side, no
test load; 2: A and B swapped; 3: A back on the test side, the test load mounted); the first
mounting check names the units with ``ref-a=<unit>``, ``ref-b=<unit>`` and ``test=<unit>``:

:data:`P3_MOUNT` ``"p3.mount"``
    An operator check that mounts the accelerometers or turns them for the 1 g tumble.
:data:`P3_TUMBLE` ``"p3.tumble"``
    A record at rest with the input axes vertical (tag ``pose=+x|-x``, the fixture axis up): K1
    and K0 of each accelerometer from ±1 g.
:data:`P3_REST` ``"p3.rest"``
    A record at rest at one of the four arm positions (tags ``arm=<deg>`` and
    ``phase=before|after`` the configuration's rates).
:data:`P3_RATE` ``"p3.rate"``
    A record spinning at one rate over whole revolutions.
:data:`P3_SWAP` ``"p3.swap"``
    The operator exchanges references A and B (an operator check, ``swap_units``).
:data:`P3_LOAD` ``"p3.load"``
    The operator puts A and B back and mounts the test accelerometer and its load
    (``swap_units`` and ``centrifuge_load_kg``).

Rate transfer (gyro scale factor, docs/rate-transfer.md) and installation errors (the
triad's misalignment angles, docs/installation.md), on a single-axis rate table; every step
after a remount carries the tag ``axis=<x|y|z>`` (the body axis up):

:data:`RATE_TRANSFER_REMOUNT`, :data:`INSTALLATION_REMOUNT` ``"<procedure>.remount"``
    The operator places the unit with another axis up (``remount``).
:data:`RATE_TRANSFER_RATE`, :data:`INSTALLATION_RATE` ``"<procedure>.rate"``
    A turn over whole revolutions (``commanded`` gives ``rate_dps`` and ``revolutions``).

P4 static tests (docs/g-sensitivity.md, docs/earth-rate-bias.md, docs/random-drift.md):

:data:`G_SENSITIVITY_POSITION` ``"g-sensitivity.position"``
    A long static record at one dual-axis table position (gravity along ±x, ±y, ±z or between).
:data:`EARTH_RATE_BIAS_REMOUNT` ``"earth-rate-bias.remount"``
    The operator places the fixture with another axis up (tag ``pose=<axis>``).
:data:`EARTH_RATE_BIAS_POSITION` ``"earth-rate-bias.position"``
    A static record at one azimuth of a single-axis table (tags ``pose=<axis>``, ``azimuth=<deg>``).
:data:`RANDOM_DRIFT_POSITION` ``"random-drift.position"``
    A static record of one repetition of the multi-position sequence (tag ``rep=<k>``).
Tumble (the accelerometer multi-position tumble of IEEE Std 1293 on a dividing head, the
dual-axis table's pitch axis; docs/tumble.md); every tumble record carries the tags
``axis=<x|y|z>`` (the body axis along the head axis), ``angle=<deg>`` (the head angle),
``positions=<N>``, ``mount=<pose>`` and ``yaw=<deg>`` (the fixture's remount), and ``pass=cw|ccw``
when both directions are run:

:data:`TUMBLE_MOUNT` ``"tumble.mount"``
    The operator places the IMU so that the body axis under test lies along the head axis.
:data:`TUMBLE_POSITION` ``"tumble.position"``
    A static record at head angle θ_k.
:data:`TUMBLE_DRIFT` ``"tumble.drift"``
    The 0° record repeated at the end of a sequence (the drift check).

Field calibration by hand (docs/field.md); the analysis finds the intervals in the continuous
IMU stream itself, the roles say what the guided session asked for:

:data:`FIELD_REST` ``"field.rest"``
    The initial rest (the static detector's reference variance).
:data:`FIELD_MOVE` ``"field.move"``
    The operator turns the unit by hand onto another face (an operator check, ``remount``).
:data:`FIELD_POSE` ``"field.pose"``
    A static record of one pose (tags ``pose<k>`` or ``turn<face><±360>``, and the face).
:data:`FIELD_TURN` ``"field.turn"``
    The operator turns the unit flat on the desk by one full turn (an operator check).

Steps that only prepare (operator checks, warm-up, moving to a start position) have no role.

:func:`role_from_tags` gives the role that the generators now set from what older plans said with
tags alone; it maps version 1 Recordings, which had no ``role`` field, and steps of hand-written
plans that carry the tags but no role.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

__all__ = [
    "ALLAN_STATIC",
    "EARTH_RATE_BIAS_POSITION",
    "EARTH_RATE_BIAS_REMOUNT",
    "FIELD_MOVE",
    "FIELD_POSE",
    "FIELD_REST",
    "FIELD_ROLES",
    "FIELD_TURN",
    "G_SENSITIVITY_POSITION",
    "INSTALLATION_RATE",
    "INSTALLATION_REMOUNT",
    "P1_ACCEL_POSITION",
    "P1_GYRO_BIAS",
    "P1_GYRO_RATE",
    "P1_HELD_OUT_POSITION",
    "P1_HELD_OUT_RATE",
    "P1_ROLES",
    "P2_RATE",
    "P2_REMOUNT",
    "P2_ROLES",
    "P2_SOAK",
    "P2_STATIC",
    "P3_LOAD",
    "P3_MOUNT",
    "P3_RATE",
    "P3_REST",
    "P3_ROLES",
    "P3_SWAP",
    "P3_TUMBLE",
    "RANDOM_DRIFT_POSITION",
    "RATE_TRANSFER_RATE",
    "RATE_TRANSFER_REMOUNT",
    "TUMBLE_DRIFT",
    "TUMBLE_MOUNT",
    "TUMBLE_POSITION",
    "TUMBLE_ROLES",
    "role_from_tags",
]

P1_ACCEL_POSITION: Final = "p1.accel-position"
P1_GYRO_BIAS: Final = "p1.gyro-bias"
P1_GYRO_RATE: Final = "p1.gyro-rate"
P1_HELD_OUT_POSITION: Final = "p1.held-out-position"
P1_HELD_OUT_RATE: Final = "p1.held-out-rate"
#: Every P1 role.
P1_ROLES: Final = (P1_ACCEL_POSITION, P1_GYRO_BIAS, P1_GYRO_RATE, P1_HELD_OUT_POSITION,
                   P1_HELD_OUT_RATE)
ALLAN_STATIC: Final = "allan.static"

P2_SOAK: Final = "p2.soak"
P2_REMOUNT: Final = "p2.remount"
P2_STATIC: Final = "p2.static"
P2_RATE: Final = "p2.rate"
#: Every P2 role.
P2_ROLES: Final = (P2_SOAK, P2_REMOUNT, P2_STATIC, P2_RATE)

P3_MOUNT: Final = "p3.mount"
P3_TUMBLE: Final = "p3.tumble"
P3_REST: Final = "p3.rest"
P3_RATE: Final = "p3.rate"
P3_SWAP: Final = "p3.swap"
P3_LOAD: Final = "p3.load"
#: Every P3 role.
P3_ROLES: Final = (P3_MOUNT, P3_TUMBLE, P3_REST, P3_RATE, P3_SWAP, P3_LOAD)

TUMBLE_MOUNT: Final = "tumble.mount"
TUMBLE_POSITION: Final = "tumble.position"
TUMBLE_DRIFT: Final = "tumble.drift"
#: Every tumble role.
TUMBLE_ROLES: Final = (TUMBLE_MOUNT, TUMBLE_POSITION, TUMBLE_DRIFT)


G_SENSITIVITY_POSITION: Final = "g-sensitivity.position"
EARTH_RATE_BIAS_REMOUNT: Final = "earth-rate-bias.remount"
EARTH_RATE_BIAS_POSITION: Final = "earth-rate-bias.position"
RANDOM_DRIFT_POSITION: Final = "random-drift.position"

FIELD_REST: Final = "field.rest"
FIELD_MOVE: Final = "field.move"
FIELD_POSE: Final = "field.pose"
FIELD_TURN: Final = "field.turn"
#: Every field role.
FIELD_ROLES: Final = (FIELD_REST, FIELD_MOVE, FIELD_POSE, FIELD_TURN)


def role_from_tags(kind: str, tags: Sequence[str], procedure: str = "") -> str:
    """Return the role a step of `kind` with `tags` has under the generators' rules, or ``""``.

    Parameters
    ----------
    kind : str
        The step kind (``"position"``, ``"static"``, ``"rate"``, …).
    tags : sequence of str
        The step's tags, e.g. ``("calibration", "six-position", "rep1")``.
    procedure : str
        The plan's ``procedure`` (``"p1"``, ``"allan"``), or ``""`` when unknown: then the
        distinctive tags decide.

    Examples
    --------
    >>> role_from_tags("position", ("calibration", "six-position", "rep1"), "p1")
    'p1.accel-position'
    >>> role_from_tags("rate", ("verification", "rate", "rep2"))
    'p1.held-out-rate'
    >>> role_from_tags("static", ("allan", "T+20"), "allan")
    'allan.static'
    """
    tagset = set(tags)
    if procedure in ("allan", "") and kind == "static" and "allan" in tagset:
        return ALLAN_STATIC
    if procedure not in ("p1", ""):
        return ""
    if kind == "position" and "six-position" in tagset:
        return P1_ACCEL_POSITION
    if kind == "static" and "gyro-bias" in tagset:
        return P1_GYRO_BIAS
    if "verification" in tagset:
        return {"position": P1_HELD_OUT_POSITION, "static": P1_HELD_OUT_POSITION,
                "rate": P1_HELD_OUT_RATE}.get(kind, "")
    if kind == "rate" and "calibration" in tagset:
        return P1_GYRO_RATE
    return ""

# Rate transfer and installation errors (docs/rate-transfer.md, docs/installation.md): every
# step after a remount carries the tag ``axis=<x|y|z>`` (the body axis up, along the table's
# spin axis); the turns also ``rate=<°/s>``.
RATE_TRANSFER_REMOUNT: Final = "rate-transfer.remount"
RATE_TRANSFER_RATE: Final = "rate-transfer.rate"
INSTALLATION_REMOUNT: Final = "installation.remount"
INSTALLATION_RATE: Final = "installation.rate"
