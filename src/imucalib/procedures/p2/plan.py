"""The plan of procedure P2: an array of IMUs on a cube, in a chamber, on a single-axis table.

:func:`generate_p2_plan` writes P2 (docs/p2.md, "The plan") as a
:class:`~imucalib.plan.schema.Plan`:

1. an operator check of the mounting (the units on the cube's faces, cables, the chamber);
2. for each temperature point, in sweep order (heating from the coldest; with
   ``hysteresis=True`` heating then cooling back, the extremes once; each point's leg the
   direction it is approached from, :func:`sweep`), a soak: the chamber ramps at
   `ramp_degc_per_min` to the point and holds until its air is within `band_degc` of the
   setpoint and every IMU's internal temperature has stayed within `imu_band_degc` for
   `stable_for_s`;
3. at each point, the six orientations of every unit: the operator places the cube with each
   of its six faces up (a remount, an operator-check step whose ``remount`` field tells the
   twin, and the operator, which face), followed by a short re-soak (the chamber was opened);
   in each pose turns at +ω and −ω over `revolutions` whole revolutions each, then two static
   records at table angles 0° and 180° (their mean cancels a tilt of the spin axis; the table
   stands still for the next remount).

``pose_order="pose-major"`` puts the six poses outermost instead: six remounts in all, each
followed by the whole temperature sweep (fewer chamber openings, six sweeps). Both orders give
every unit, at every temperature point, each of its body axes up and down — an IMU on any face
of the cube sees every orientation over the six poses; the analysis finds which from its
static accelerometer means.

Every step has a role (:mod:`.roles`: ``p2.soak``, ``p2.remount``,
``p2.static``, ``p2.rate``) and the tags ``point=<k>`` and ``leg=heating|cooling``
(``held-out`` on the points the temperature models must predict without using them),
``pose=<axis>`` and, for static records, ``angle=<deg>``.

The plan carries a ``[twin]`` table: a lab-grade single-axis table in a chamber, the cube
(hexahedral fixture) with `n_imus` units of the chosen grade.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from imucalib.errors import ConfigurationError
from imucalib.plan.bounds import MAX_IMUS
from imucalib.plan.equipment import (
    ChamberConfig,
    FixtureConfig,
    ImuConfig,
    SiteConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.plan.fixture_poses import FixtureAxis
from imucalib.plan.schema import (
    GuardConfig,
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    PositionStep,
    RateStep,
    SoakStep,
)
from imucalib.procedures.p2.roles import P2_RATE, P2_REMOUNT, P2_SOAK, P2_STATIC

__all__ = [
    "DEFAULT_HELD_OUT_DEGC",
    "DEFAULT_TEMPERATURES_DEGC",
    "POSES",
    "generate_p2_plan",
    "sweep",
]

#: Calibration temperature points [°C] (−40 … +85 °C, the industrial range).
DEFAULT_TEMPERATURES_DEGC: tuple[float, ...] = (-40.0, -20.0, 0.0, 25.0, 45.0, 65.0, 85.0)
#: Temperature points held out of the temperature-model fit, to check its predictions [°C].
DEFAULT_HELD_OUT_DEGC: tuple[float, ...] = (-10.0, 55.0)
#: The six poses of the cube: which fixture axis points up.
POSES: tuple[FixtureAxis, ...] = ("+z", "-z", "+y", "-y", "+x", "-x")
#: Held-out accuracy of the compensated model per grade (accelerometer [g], gyro [°/s]).
GRADE_ACCURACY: dict[str, tuple[float, float]] = {
    "consumer": (0.01, 0.5), "tactical": (1e-3, 0.05), "navigation": (1e-4, 0.005)}


def sweep(temperatures_degc: Sequence[float], held_out_degc: Sequence[float], *,
          hysteresis: bool, start_degc: float = 25.0) -> list[tuple[float, str, bool]]:
    """Return the temperature points in visiting order: (temperature, leg, held out).

    Heating from the coldest point to the hottest; with `hysteresis`, then cooling back to the
    second coldest (the hottest point is visited once). A point's leg is the direction it is
    approached from — the coldest, reached first from `start_degc` (the chamber's temperature
    before the run), is on the cooling leg when it lies below it: thermal hysteresis depends
    on where the temperature came from, not on the plan's intent.

    Raises
    ------
    ConfigurationError
        Fewer than two calibration points, a repeated temperature, or a held-out point that is
        also a calibration point.
    """
    cal = [float(t) for t in temperatures_degc]
    held = [float(t) for t in held_out_degc]
    if len(cal) < 2:
        raise ConfigurationError(f"P2 needs at least 2 calibration temperatures; got {cal}")
    every = cal + held
    dup = sorted({t for t in every if every.count(t) > 1})
    if dup:
        raise ConfigurationError(f"temperature points must be distinct; repeated {dup} (a "
                                 "held-out point must not also be a calibration point)")
    points = sorted((t, t in held) for t in every)
    visits = points + (list(reversed(points[1:-1])) if hysteresis else [])
    order = []
    previous = float(start_degc)
    for t, h in visits:
        order.append((t, "heating" if t > previous else "cooling", h))
        previous = t
    return order


def _twin(n_imus: int, grade: str, sample_rate_hz: float, seed: int, half_edge_m: float,
          temperatures: Sequence[float], start_degc: float) -> TwinEquipment:
    lo, hi = min(temperatures), max(temperatures)
    return TwinEquipment(
        seed=seed,
        site=SiteConfig(latitude_deg=45.0, ambient_temperature_degc=start_degc),
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=start_degc,
                              min_temperature_degc=min(lo - 15.0, -55.0),
                              max_temperature_degc=max(hi + 15.0, 125.0),
                              max_ramp_degc_per_min=10.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=half_edge_m),
        imus=tuple(ImuConfig(name=f"IMU-{i + 1:04d}", grade=grade,
                             sample_rate_hz=sample_rate_hz, thermal_time_constant_s=300.0)
                   for i in range(n_imus)),
    )


def generate_p2_plan(
    *,
    n_imus: int = 8,
    grade: str = "consumer",
    temperatures_degc: Sequence[float] = DEFAULT_TEMPERATURES_DEGC,
    held_out_degc: Sequence[float] = DEFAULT_HELD_OUT_DEGC,
    hysteresis: bool = False,
    rate_dps: float = 60.0,
    revolutions: int = 2,
    static_s: float = 10.0,
    settle_s: float = 10.0,
    ramp_degc_per_min: float = 2.0,
    band_degc: float = 0.5,
    imu_band_degc: float = 0.2,
    stable_for_s: float = 900.0,
    resoak_s: float = 120.0,
    soak_timeout_s: float = 14400.0,
    pose_order: Literal["temperature-major", "pose-major"] = "temperature-major",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    half_edge_m: float = 0.06,
    twin: TwinEquipment | None = None,
    start_degc: float = 25.0,
    name: str = "p2-array-temperature",
) -> Plan:
    """Return procedure P2's plan (module docstring).

    Parameters
    ----------
    n_imus : int
        Units on the cube, 1 … 64 (the twin's; a real station's are whatever is mounted).
    grade : {"consumer", "tactical", "navigation"}
        The units' grade: the twin's IMUs and the held-out accuracy limits.
    temperatures_degc, held_out_degc : sequence of float
        Calibration and held-out temperature points. [°C]
    hysteresis : bool
        Visit the points heating then cooling (the models get a hysteresis term).
    rate_dps : float
        |ω| of the turns. [°/s]
    revolutions : int
        Whole revolutions recorded per turn.
    static_s, settle_s : float
        Record length of each static window, settling before each record. [s]
    ramp_degc_per_min, band_degc, imu_band_degc, stable_for_s, resoak_s, soak_timeout_s :
        The soak criteria (the re-soak after a remount holds for `resoak_s`; 0: none).
    pose_order : {"temperature-major", "pose-major"}
        Six remounts at every temperature, or six temperature sweeps.
    sample_rate_hz, seed, half_edge_m : float, int, float
        The twin's IMU rate, seed and cube half edge.
    twin : TwinEquipment, optional
        Another twin station (its IMUs replace `n_imus`).
    start_degc : float
        The chamber's temperature before the run (the first point's leg, :func:`sweep`). [°C]
    name : str
        The plan's name.

    Raises
    ------
    ConfigurationError
        Options out of range.
    """
    if not 1 <= n_imus <= MAX_IMUS:
        raise ConfigurationError(f"`n_imus` must be 1 … {MAX_IMUS}; got {n_imus}")
    if grade not in GRADE_ACCURACY:
        raise ConfigurationError(f"`grade` must be one of {sorted(GRADE_ACCURACY)}; got "
                                 f"{grade!r}")
    if pose_order not in ("temperature-major", "pose-major"):
        raise ConfigurationError(f"`pose_order` must be 'temperature-major' or 'pose-major'; "
                                 f"got {pose_order!r}")
    if rate_dps <= 0.0 or revolutions < 1:
        raise ConfigurationError(f"`rate_dps` must be > 0 and `revolutions` ≥ 1; got "
                                 f"{rate_dps:g}, {revolutions}")
    order = sweep(temperatures_degc, held_out_degc, hysteresis=hysteresis,
                  start_degc=start_degc)
    temps = [t for t, _, _ in order]
    equipment = twin if twin is not None else _twin(
        n_imus, grade, sample_rate_hz, seed, half_edge_m, temps, start_degc)
    steps: list[PlanStep] = [OperatorCheckStep(
        kind="operator-check",
        item=(f"{len(equipment.imus)} units on the cube's faces, square to the faces, cables "
              "strain-relieved, chamber closed; the cube stands with face +z up"))]

    def point_tags(k: int, leg: str, held: bool) -> tuple[str, ...]:
        return (f"point={k}", f"leg={leg}", *(("held-out",) if held else ()))

    def soak(k: int, temp: float, leg: str, held: bool, stable_s: float, what: str) -> SoakStep:
        return SoakStep(kind="soak", temperature_degc=temp, ramp_degc_per_min=ramp_degc_per_min,
                        band_degc=band_degc, imu_band_degc=imu_band_degc,
                        stable_for_s=stable_s, timeout_s=max(soak_timeout_s, stable_s),
                        role=P2_SOAK, tags=point_tags(k, leg, held),
                        label=f"{what} {temp:+g} °C ({leg})")

    def pose_steps(k: int, temp: float, leg: str, held: bool, pose: str) -> list[PlanStep]:
        tags = (*point_tags(k, leg, held), f"pose={pose}")
        where = f"{temp:+g} °C {leg}, {pose} up"
        # the turns first, the static records last: the table stands still when the operator
        # remounts the cube after them
        out: list[PlanStep] = [
            RateStep(kind="rate", axis=0, rate_dps=sign * rate_dps, settle_s=settle_s,
                     revolutions=revolutions, role=P2_RATE, tags=tags,
                     label=f"{where}, {sign * rate_dps:+g} °/s")
            for sign in (1.0, -1.0)]
        out += [PositionStep(kind="position", angles_deg=(angle,), settle_s=settle_s,
                             record_s=static_s, role=P2_STATIC,
                             tags=(*tags, f"angle={angle:g}"),
                             label=f"{where}, static {angle:g}°")
                for angle in (0.0, 180.0)]
        return out

    def remount(k: int, temp: float, leg: str, held: bool, pose: FixtureAxis
                ) -> OperatorCheckStep:
        return OperatorCheckStep(
            kind="operator-check", remount=pose,
            item=f"open the chamber, place the cube with its {pose} face up, close the chamber",
            role=P2_REMOUNT, tags=(*point_tags(k, leg, held), f"pose={pose}"),
            label=f"remount {pose} up")

    if pose_order == "temperature-major":
        for k, (temp, leg, held) in enumerate(order):
            steps.append(soak(k, temp, leg, held, stable_for_s, "soak"))
            for pose in POSES:
                steps.append(remount(k, temp, leg, held, pose))
                if resoak_s > 0.0:  # 0: no re-soak (the option's minimum)
                    steps.append(soak(k, temp, leg, held, resoak_s, "re-soak"))
                steps += pose_steps(k, temp, leg, held, pose)
    else:
        for pose in POSES:
            steps.append(remount(0, order[0][0], order[0][1], order[0][2], pose))
            for k, (temp, leg, held) in enumerate(order):
                steps.append(soak(k, temp, leg, held, stable_for_s, "soak"))
                steps += pose_steps(k, temp, leg, held, pose)
    accel_g, gyro_dps = GRADE_ACCURACY[grade]
    lo, hi = min(temps), max(temps)
    return Plan(
        name=name,
        description=("P2 (docs/p2.md): an array of IMUs on a cube in a thermal chamber on a "
                     "single-axis table; six orientations × static and ±ω at every "
                     "temperature point; temperature models of every parameter."),
        procedure="p2",
        imu=ImuSpecConfig(grade=grade, accel_accuracy_g=accel_g,
                          gyro_accuracy_dps=gyro_dps),
        limits=PlanLimits(max_rate_dps=max(rate_dps * 1.5, 100.0),
                          min_temperature_degc=min(lo - 10.0, -55.0),
                          max_temperature_degc=max(hi + 10.0, 125.0)),
        # the table angle enters only through the 0°/180° pair (a tilt cancels whatever the
        # angle error): a lab-grade table holding 60″ suffices
        guards=GuardConfig(chamber_band_degc=max(1.0, band_degc), position_tolerance_arcsec=60.0),
        twin=equipment,
        steps=tuple(steps),
    )

