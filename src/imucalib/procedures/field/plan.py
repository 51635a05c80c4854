"""The guided session of the field calibration: what the operator does, step by step.

:func:`generate_field_plan` writes a plan for a hand-held session with no equipment but the
IMU: the IMU logs continuously while the operator follows the operator checks: put it down
and leave it still (the detector's initial rest), then, pose after pose, "turn it by hand so
that its +x face points up, tilted freely, and let go", each followed by a short static record
(role ``field.pose``); optionally, full turns flat on the desk about each axis, one
counter-clockwise and one clockwise (role ``field.turn``), for the known-angle gyro form of
Ferraris et al. (1995). The analysis does not rely on the steps: it finds the static intervals
and the rotations in the continuous IMU stream (docs/field.md), so the same analysis runs on
a CSV logged without a plan.

Each operator check names the face up as its ``remount``, so that ``imucalib run PLAN --station
sim`` runs the plan on the twin, whose operator places the unit exactly on that face (the
twin cannot turn a unit by hand: it has no rotation between poses and no tilt; the hand-held
twin sessions of :mod:`imucalib.sim.handheld` simulate those). The output-jump guards allow
2.5 g and 1000 °/s between samples: a unit turned over by hand, or remounted on the twin,
jumps by up to 2 g.

Contents
--------
:func:`generate_field_plan`.
"""

from __future__ import annotations

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.schema import (
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanStep,
    StaticStep,
)
from imucalib.procedures.field.roles import FIELD_MOVE, FIELD_POSE, FIELD_REST, FIELD_TURN

__all__ = ["generate_field_plan"]

_FACES = ("+z", "-z", "+x", "-x", "+y", "-y")
_GRADES = ("consumer", "tactical", "navigation")


def generate_field_plan(*, name: str = "field", grade: str = "consumer", n_poses: int = 12,
                        static_s: float = 6.0, init_static_s: float = 10.0,
                        full_turns: bool = True, tilt_deg: float = 20.0,
                        sample_rate_hz: float = 200.0, latitude_deg: float = 45.0,
                        seed: int = 1) -> Plan:
    """Return the guided session's plan (module docstring).

    Parameters
    ----------
    name : str
        Plan name.
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade (the twin's IMU).
    n_poses : int
        Static poses after the initial rest (≥ 6; the faces in turn, the second round tilted
        by about `tilt_deg` so that the non-orthogonality is seen; ≥ 10 for the gravity-norm
        form).
    static_s : float
        Each pose's record (≥ 2 s: the detector's windows eat half a second at each end). [s]
    init_static_s : float
        The initial rest. [s]
    full_turns : bool
        Add a +360° and a −360° turn flat on the desk about each axis.
    tilt_deg : float
        How far the operator tilts the second round of poses. [°]
    sample_rate_hz, latitude_deg, seed
        The twin's IMU rate, site and seed.

    Raises
    ------
    ConfigurationError
        An unknown grade, fewer than six poses, records too short.
    """
    if grade not in _GRADES:
        raise ConfigurationError(f"`grade` must be one of {list(_GRADES)}; got {grade!r}")
    if n_poses < 6:
        raise ConfigurationError(f"`n_poses` must be at least 6 (every face up once); got "
                                 f"{n_poses}")
    if static_s < 2.0 or init_static_s < 4.0:
        raise ConfigurationError(f"`static_s` must be ≥ 2 s and `init_static_s` ≥ 4 s; got "
                                 f"{static_s:g} s and {init_static_s:g} s")
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="set-up", remount="+z",
                          item="Start logging the IMU continuously (do not stop until the end); "
                               "put it on a flat, still desk with its +z face up and do not "
                               "touch it or the desk", role=FIELD_MOVE),
        StaticStep(kind="static", label="initial rest", duration_s=init_static_s,
                   role=FIELD_REST, tags=("rest",)),
    ]
    for k in range(n_poses):
        face = _FACES[k % 6]
        tilted = k >= 6
        how = (f", leaning about {tilt_deg:g}° on one of its edges (any edge, any heading)"
               if tilted else " (a few degrees off is fine; any heading)")
        steps += [
            OperatorCheckStep(kind="operator-check", label=f"pose {k + 1}: {face} up",
                              remount=face, remount_yaw_deg=float((37 * k) % 360),
                              item=f"Turn the IMU by hand so that its {face} face points up"
                                   f"{how}; set it down and let go", role=FIELD_MOVE),
            StaticStep(kind="static", label=f"pose {k + 1}", duration_s=static_s,
                       role=FIELD_POSE, tags=(f"pose{k + 1}", face)),
        ]
    if full_turns:
        for face in ("+z", "+x", "+y"):
            for sense, word in ((+1, "counter-clockwise"), (-1, "clockwise")):
                steps += [
                    OperatorCheckStep(
                        kind="operator-check", label=f"turn {face} {sense * 360:+d}°",
                        remount=face,
                        item=f"With its {face} face up and flat on the desk, turn the IMU "
                             f"one full turn {word} seen from above, keeping it flat and in "
                             "place; set it still where it started", role=FIELD_TURN),
                    StaticStep(kind="static", label=f"after turn {face} {sense * 360:+d}°",
                               duration_s=static_s, role=FIELD_POSE,
                               tags=(f"turn{face}{sense * 360:+d}", face)),
                ]
    twin = TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=latitude_deg),
        table=TableConfig(kind="single-axis", grade="ideal"),
        imus=(ImuConfig(name="IMU-0001", grade=grade, sample_rate_hz=sample_rate_hz),))
    return Plan(name=name,
                description=f"field calibration by hand: {n_poses} poses"
                            + (", full turns about each axis" if full_turns else ""),
                procedure="field", imu=ImuSpecConfig(grade=grade), twin=twin,
                guards=GuardConfig(accel_jump_g=2.5, gyro_jump_dps=1000.0),
                steps=tuple(steps))
