"""The plan of the tumble: an accelerometer multi-position test on a dividing head.

:func:`generate_tumble_plan` writes the tumble (docs/tumble.md, "The plan") as a
:class:`~imucalib.plan.schema.Plan`. The dividing head is the dual-axis table's outer axis
(pitch, about −y_t: horizontal); the inner axis (roll, about x_p) and the fixture's mounting put
the chosen body axis along it (:data:`HEAD_MOUNTS`):

=====  ==================  =====  ===================================================
axis   mount (pose, yaw)   roll   body axis along the head axis n_pitch = −y_t
=====  ==================  =====  ===================================================
x      +z, 90°             0°     x_b = +y_p, so n_pitch = −x_b
y      +z, 0°              0°     n_pitch = −y_b
z      +z, 0°              90°    n_pitch = +z_b (R_x(90°)ᵀ·(0, −1, 0))
=====  ==================  =====  ===================================================

For each head axis: an operator check (role ``tumble.mount``: the remount), then the head
stepped through N equally spaced angles θ_k = 360°·k/N (role ``tumble.position``, tags
``axis=``, ``angle=``, ``positions=``, ``mount=``, ``yaw=``), and the 0° record repeated at the
end (role ``tumble.drift``: the drift check). With ``both_directions=True`` the sequence is
followed by its reverse (tags ``pass=cw`` and ``pass=ccw``), each ending at 0°.

The head turns gravity in the body plane ⟂ the head axis: the two accelerometers in that plane
are tested at each head axis (x and y at head axis z, …), so three head axes test each
accelerometer twice and resolve all six misalignments.

The plan carries a ``[twin]`` table: a dual-axis "high"-grade table and one IMU of `grade`.
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.schema import (
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    PositionStep,
)
from imucalib.procedures.tumble.roles import TUMBLE_DRIFT, TUMBLE_MOUNT, TUMBLE_POSITION

__all__ = ["HEAD_MOUNTS", "UNIT_NAME", "generate_tumble_plan", "head_angles_deg"]

#: Body axis along the head axis → (fixture pose, yaw [°], roll angle [°]) (module docstring).
HEAD_MOUNTS: dict[str, tuple[str, float, float]] = {
    "x": ("+z", 90.0, 0.0), "y": ("+z", 0.0, 0.0), "z": ("+z", 0.0, 90.0)}
#: The twin's unit.
UNIT_NAME = "IMU-0001"
#: Fewest positions: K0, K1, δ and K2 − Kpp need four (docs/tumble.md, Table T.1).
MIN_POSITIONS = 4


def head_angles_deg(n_positions: int) -> list[float]:
    """Return the N equally spaced head angles 360°·k/N, k = 0 … N − 1.

    Raises
    ------
    ConfigurationError
        N below 4 or not a divisor of 360 (the angles must be whole table steps).
    """
    if not isinstance(n_positions, int) or n_positions < MIN_POSITIONS or 360 % n_positions:
        raise ConfigurationError(f"`n_positions` must be an integer ≥ {MIN_POSITIONS} dividing "
                                 f"360 (4, 8, 12, 24 …); got {n_positions!r}")
    return [360.0 * k / n_positions for k in range(n_positions)]


def generate_tumble_plan(
    *,
    n_positions: int = 12,
    axes: Sequence[str] = ("x", "y", "z"),
    record_s: float = 30.0,
    settle_s: float = 10.0,
    both_directions: bool = False,
    grade: str = "navigation",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    twin: TwinEquipment | None = None,
    name: str = "tumble",
) -> Plan:
    """Return the tumble plan (module docstring).

    Parameters
    ----------
    n_positions : int
        Head positions per sequence (≥ 4, dividing 360: 4, 8, 12, 24 …).
    axes : sequence of {"x", "y", "z"}
        The body axes put along the head axis, in order.
    record_s, settle_s : float
        Record length at each position and settling before it. [s]
    both_directions : bool
        Each sequence also in reverse (hysteresis shows as the passes' difference).
    grade, sample_rate_hz, seed :
        The twin's unit.
    twin : TwinEquipment, optional
        Another twin station (a dual-axis table).
    name : str
        The plan's name.

    Raises
    ------
    ConfigurationError
        Options out of range: N, an unknown or repeated axis, record lengths not positive.
    """
    angles = head_angles_deg(n_positions)
    axes = tuple(axes)
    if not axes or any(a not in HEAD_MOUNTS for a in axes) or len(set(axes)) != len(axes):
        raise ConfigurationError(f"`axes` must be distinct names of {sorted(HEAD_MOUNTS)}; got "
                                 f"{list(axes)}")
    if not record_s > 0 or settle_s < 0:
        raise ConfigurationError(f"`record_s` must be positive and `settle_s` ≥ 0; got "
                                 f"{record_s!r}, {settle_s!r}")
    equipment = twin if twin is not None else TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=45.0),
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name=UNIT_NAME, grade=grade, sample_rate_hz=sample_rate_hz),))
    passes = (("cw", angles), ("ccw", [angles[0], *angles[:0:-1]])) if both_directions else (
        ("", angles),)
    steps: list[PlanStep] = []
    for axis in axes:
        pose, yaw, roll = HEAD_MOUNTS[axis]
        steps.append(OperatorCheckStep(
            kind="operator-check", role=TUMBLE_MOUNT, remount=pose, remount_yaw_deg=yaw,
            tags=(f"axis={axis}",),
            item=(f"mount the IMU with its {pose} axis up, turned {yaw:g}° about the vertical: "
                  f"at roll {roll:g}° its {axis} axis lies along the dividing head's axis"),
            label=f"head axis along {axis}"))
        for direction, sequence in passes:
            common = (f"axis={axis}", f"positions={n_positions}", f"mount={pose}",
                      f"yaw={yaw:g}", *((f"pass={direction}",) if direction else ()))
            what = f" ({direction})" if direction else ""
            for theta in sequence:
                steps.append(PositionStep(
                    kind="position", angles_deg=(theta, roll), settle_s=settle_s,
                    record_s=record_s, role=TUMBLE_POSITION, tags=(*common, f"angle={theta:g}"),
                    label=f"head {axis}{what}: {theta:g}°"))
            steps.append(PositionStep(
                kind="position", angles_deg=(angles[0], roll), settle_s=settle_s,
                record_s=record_s, role=TUMBLE_DRIFT, tags=(*common, f"angle={angles[0]:g}"),
                label=f"head {axis}{what}: {angles[0]:g}° again (drift check)"))
    return Plan(
        name=name,
        description=(f"Tumble (docs/tumble.md): the accelerometers on a dividing head (the "
                     f"table's pitch axis), {n_positions} positions about each of the body axes "
                     f"{', '.join(axes)}; IEEE Std 1293 multipoint tumble."),
        procedure="tumble",
        imu=ImuSpecConfig(grade=grade),
        limits=PlanLimits(),
        guards=GuardConfig(),
        twin=equipment,
        steps=tuple(steps),
    )
